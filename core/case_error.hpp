#pragma once
#include <stdexcept>
#include <string>

namespace core {

/// A problem with a load case. The message always names the file, the JSON path (RFC 6901 pointer,
/// e.g. `/material/K1`) and what was expected, so the user can fix the config without reading code.
class CaseError : public std::runtime_error {
 public:
  CaseError(const std::string& file, const std::string& json_path, const std::string& what_expected)
      : std::runtime_error(file + ": " + (json_path.empty() ? std::string("/") : json_path) + ": " +
                           what_expected),
        file_(file),
        json_path_(json_path) {}
  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }

 private:
  std::string file_;
  std::string json_path_;
};

}  // namespace core
