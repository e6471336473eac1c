#pragma once
// A private Open MPI session directory for a program started without mpirun (an MPI "singleton").
//
// Every program here initialises MPI, even for one process (dealii::Utilities::MPI::MPI_InitFinalize). Open MPI 4.1
// (Debian 12) then starts a daemon and keeps its session files under one directory shared by all of the user's
// jobs, <tmp>/ompi.<host>.<uid>. Two singletons that start and stop at the same moment race on it: the one that
// finalises removes the shared directory while the other is creating its own files under it, and the second aborts
// in MPI_Init ("A call to mkdir was unable to create the desired directory ... File exists", open-mpi/ompi#8510).
// This happened under `ctest -j2`, where two tests each ran `tissue`, and can happen to anyone running several
// `tissue` commands side by side (a sweep under xargs -P, say).
//
// The fix: before MPI_Init, give this process its own base directory for those files (the MCA parameter
// orte_tmpdir_base, through its environment variable), and remove it after MPI_Finalize.
//
// Lifetime: construct before dealii::Utilities::MPI::MPI_InitFinalize and destroy after it, i.e. declare it first in
// main(); construct it after core::use_supported_openblas_kernel(), which may execute the program again.
// Thread safety: construct and destroy on the main thread while no other thread runs (it calls setenv).
#include <string>

namespace core {

class SingletonMpiSessionDirectory {
 public:
  /// Creates <TMPDIR or /tmp>/tissue-mpi-XXXXXX and sets OMPI_MCA_orte_tmpdir_base to it. Does nothing when the
  /// process was started by a launcher (mpirun, srun: it has the session directory of its job), when the user
  /// set OMPI_MCA_orte_tmpdir_base, or when the directory cannot be made (Open MPI's default then applies).
  SingletonMpiSessionDirectory();
  /// Removes the directory and all that Open MPI left in it.
  ~SingletonMpiSessionDirectory();

  SingletonMpiSessionDirectory(const SingletonMpiSessionDirectory&) = delete;
  SingletonMpiSessionDirectory& operator=(const SingletonMpiSessionDirectory&) = delete;

  /// The private base directory; empty when the constructor did nothing.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace core
