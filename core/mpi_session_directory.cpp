#include "core/mpi_session_directory.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace core {
namespace {

/// Variables a launcher sets in each process it starts: Open MPI's mpirun, PMIx, and PMI (Slurm's srun, MPICH).
bool started_by_a_launcher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

}  // namespace

SingletonMpiSessionDirectory::SingletonMpiSessionDirectory() {
  constexpr const char* kVariable = "OMPI_MCA_orte_tmpdir_base";
  if (started_by_a_launcher() || std::getenv(kVariable) != nullptr) return;
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/tissue-mpi-XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (mkdtemp(buffer.data()) == nullptr) return;
  path_ = buffer.data();
  if (setenv(kVariable, path_.c_str(), 1) != 0) {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
    path_.clear();
  }
}

SingletonMpiSessionDirectory::~SingletonMpiSessionDirectory() {
  if (path_.empty()) return;
  std::error_code ignored;  // a file the daemon is still removing: nothing to report at exit
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace core
