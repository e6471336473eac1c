#pragma once
// Results are written into a hidden staging folder next to the destination and moved into place only
// when the run succeeds, so a failed or interrupted run never leaves half-written results behind.
#include <filesystem>
#include <string>

namespace core {

class OutputDirectory {
 public:
  /// @param destination  the folder the user asked for; created (with parents) on commit()
  explicit OutputDirectory(const std::filesystem::path& destination);
  ~OutputDirectory();  ///< removes the staging folder unless commit() succeeded
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  /// Path of a file inside the staging folder (write here).
  std::filesystem::path file(const std::string& relative) const;
  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }

  /// Move every staged file into the destination (replacing files of the same name).
  void commit();

 private:
  std::filesystem::path destination_;
  std::filesystem::path staging_;
  std::filesystem::path created_ancestor_;  // first folder this object created, removed on failure
  bool committed_ = false;
};

}  // namespace core
