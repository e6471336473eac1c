#pragma once
// The surrogate file `tissue fit` writes and `tissue probe` reads: one JSON document with a format name and
// version, the hash of the case it was trained on, its units, the fitted coefficients (eqs. 25-28), the
// surface nodes and the training report, sealed by a SHA-256 checksum of its content (docs/SURROGATE.md §5).
//
// Reading checks the format version, the units and the checksum, and the case hash when the caller has the
// case; a missing, truncated, edited or mismatched file throws SurrogateFileError with the file name, what is
// wrong and what to do. Writing is atomic: a temporary file in the same folder, renamed over the destination
// when complete.
#include <optional>
#include <stdexcept>
#include <string>

#include "core/case.hpp"
#include "meshless/surrogate/surrogate.hpp"

namespace meshless {

constexpr int kSurrogateFormatVersion = 1;

class SurrogateFileError : public std::runtime_error {
 public:
  SurrogateFileError(const std::string& file, const std::string& what)
      : std::runtime_error(file + ": " + what), file_(file) {}
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

/// SHA-256 (hex) of what a surrogate depends on: the case document without the keys that cannot change it
/// (description, samples, fem, output), serialised canonically (sorted keys), followed by the bytes of the
/// STL file for STL geometry.
std::string surrogate_case_hash(const core::Case& c);

/// Write atomically. Throws SurrogateFileError when the folder is not writable or the disk is full.
void write_surrogate(const std::string& path, const SurrogateData& data);

/// Read and check. `expected_case_hash`: when given, a surrogate of another case (or of this case before an
/// edit) is refused.
SurrogateData read_surrogate(const std::string& path,
                             const std::optional<std::string>& expected_case_hash = std::nullopt);

}  // namespace meshless
