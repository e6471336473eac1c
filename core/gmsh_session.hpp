#pragma once
// RAII around the Gmsh SDK's global state: initialise quietly, always finalise (also on exceptions).
// Gmsh is a process-wide singleton, so only one session may be alive at a time.
namespace core {

class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

}  // namespace core
