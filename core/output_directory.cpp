#include "core/output_directory.hpp"

#include <unistd.h>

#include <chrono>

namespace core {
namespace fs = std::filesystem;

OutputDirectory::OutputDirectory(const fs::path& destination) : destination_(fs::absolute(destination)) {
  const fs::path parent = destination_.parent_path();
  for (fs::path p = parent; !p.empty() && !fs::exists(p); p = p.parent_path()) created_ancestor_ = p;
  fs::create_directories(parent);
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  staging_ = parent / ("." + destination_.filename().string() + ".partial-" + std::to_string(::getpid()) +
                       "-" + std::to_string(stamp));
  fs::create_directories(staging_);
}

OutputDirectory::~OutputDirectory() {
  std::error_code ec;
  if (committed_) return;
  fs::remove_all(staging_, ec);
  // Folders created only for this run are removed too: a failed run leaves nothing behind.
  if (!created_ancestor_.empty()) fs::remove_all(created_ancestor_, ec);
}

fs::path OutputDirectory::file(const std::string& relative) const {
  const fs::path p = staging_ / relative;
  fs::create_directories(p.parent_path());
  return p;
}

void OutputDirectory::commit() {
  if (!fs::exists(destination_)) {
    fs::rename(staging_, destination_);
  } else {
    for (const auto& entry : fs::recursive_directory_iterator(staging_)) {
      if (!entry.is_regular_file()) continue;
      const fs::path target = destination_ / fs::relative(entry.path(), staging_);
      fs::create_directories(target.parent_path());
      fs::rename(entry.path(), target);
    }
    fs::remove_all(staging_);
  }
  committed_ = true;
}

}  // namespace core
