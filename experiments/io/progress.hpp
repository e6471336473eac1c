#pragma once
// Progress lines on stderr for anything that may take more than a few seconds:
//   [case mesh 1/3] building geometry and meshes (Gmsh) ... (0.0 s)
#include <chrono>
#include <string>

namespace experiments {

/// Thrown from a CLI11 callback to hand the exit code back to main().
struct CommandResult {
  int exit_code;
};

class Progress {
 public:
  /// `quiet`: count and time the steps but print nothing (the MPI processes other than rank 0).
  Progress(std::string task, int total_steps, bool quiet = false);
  void step(const std::string& what);  ///< announce the next step
  void note(const std::string& what);  ///< a line within the current step (news of work running elsewhere)
  void done();                         ///< announce completion with the elapsed time
  double elapsed_seconds() const;

 private:
  std::string task_;
  int total_;
  int current_ = 0;
  bool quiet_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace experiments
