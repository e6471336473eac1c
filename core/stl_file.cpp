#include "core/stl_file.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <vector>

namespace core {

std::string check_stl_layout(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return fmt::format("expected a readable STL file, but \"{}\" cannot be opened", file);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string text(bytes.begin(), bytes.end());
  // Gmsh reads the file as ASCII when it starts with "solid" and it finds vertices, and as binary otherwise (some
  // binary files start their header with "solid" too).
  const bool solid = text.rfind("solid", 0) == 0 || text.rfind("SOLID", 0) == 0;
  if (solid && (text.find("vertex") != std::string::npos || text.find("VERTEX") != std::string::npos)) return {};
  const std::string kinds = solid ? "an ASCII STL with facets (\"vertex x y z\" lines) or a binary STL"
                                  : "an ASCII STL (starting with \"solid\") or a binary STL";
  if (bytes.size() < 84)
    return fmt::format("expected {} (80-byte header, triangle count, 50 bytes per triangle), but \"{}\" is neither "
                       "({} bytes)",
                       kinds, file, bytes.size());
  std::uint32_t count = 0;
  for (int i = 3; i >= 0; --i) count = (count << 8) | static_cast<unsigned char>(bytes[80 + i]);  // little endian
  const std::uint64_t expected = 84 + 50 * static_cast<std::uint64_t>(count);
  if (expected != bytes.size())
    return fmt::format(
        "expected {}; read as binary, its header announces {} triangles, which take 84 + 50 x {} = {} bytes, but "
        "\"{}\" has {} bytes: the file is truncated or not an STL",
        kinds, count, count, expected, file, bytes.size());
  return {};
}

}  // namespace core
