// libFuzzer target: the case reader on arbitrary bytes (core::parse_case_text, as `tissue` reads a config).
// Every input must either give a Case or a core::CaseError naming the file, the JSON path and what was
// expected; any other exception, a crash or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "core/case.hpp"
#include "core/load_program.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const core::Case c = core::parse_case_text(text, "fuzz/case.json");
    // What the models derive from a valid case without a mesh must be finite and consistent.
    if (!(c.time.dt() > 0.0) || !(c.time.minimum_step() > 0.0) || c.time.minimum_step() > c.time.dt() ||
        !c.load.force.allFinite() || !(c.geometry.mesh_size > 0.0)) {
      std::fprintf(stderr, "parse_case accepted an inconsistent case\n");
      std::abort();
    }
  } catch (const core::CaseError& e) {
    if (std::string(e.what()).find("fuzz/case.json") != 0) {
      std::fprintf(stderr, "CaseError without the file name: %s\n", e.what());
      std::abort();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "parse_case threw something other than CaseError: %s\n", e.what());
    std::abort();
  }
  return 0;
}
