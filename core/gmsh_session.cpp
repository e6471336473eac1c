#include "core/gmsh_session.hpp"

#include <gmsh.h>
#include <omp.h>

#include <cstdlib>
#include <stdexcept>

namespace core {

static bool g_session_alive = false;

GmshSession::GmshSession() {
  if (g_session_alive) throw std::logic_error("GmshSession: a Gmsh session is already open");
  omp_threads_ = omp_get_max_threads();
  gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
  gmsh::option::setNumber("General.Terminal", std::getenv("TISSUE_GMSH_VERBOSE") ? 1 : 0);
  gmsh::option::setNumber("General.Verbosity", std::getenv("TISSUE_GMSH_VERBOSE") ? 5 : 1);
  g_session_alive = true;
}

GmshSession::~GmshSession() {
  gmsh::finalize();
  omp_set_num_threads(omp_threads_);  // General.NumThreads changed it for the whole process (header)
  g_session_alive = false;
}

}  // namespace core
