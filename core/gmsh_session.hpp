#pragma once
// RAII around the Gmsh SDK's global state: initialise quietly, always finalise (also on exceptions).
// Gmsh is a process-wide singleton, so only one session may be alive at a time.
//
// Gmsh's option General.NumThreads (set to 1 for deterministic meshes, core/geometry.cpp) calls
// omp_set_num_threads, which changes the OpenMP thread count of the whole process and outlives the session: every
// OpenMP loop after the meshing (the EFG model's tabulation and assembly) then ran on one core. The session
// therefore restores the thread count it found when it ends.
namespace core {

class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  int omp_threads_ = 1;  ///< omp_get_max_threads() when the session began
};

}  // namespace core
