#pragma once
// What a load case asks of a model, stated once for both of them: the case (core::Case) and the model's own
// tagged mesh become the loads and times the model applies. The meshless model (meshless::problem_from_case)
// and the FEM reference (reference_fem::run_case) both read this, so the traction, the ramp and the step times
// cannot drift apart between them.
#include <Eigen/Core>
#include <vector>

#include "core/case.hpp"
#include "core/tet_mesh.hpp"

namespace core {

/// The loading programme of a case on one mesh.
struct LoadProgram {
  /// Uniform traction on the faces tagged FaceTag::load at full load: force / patch_area [Pa].
  Eigen::Vector3d traction = Eigen::Vector3d::Zero();
  double patch_area = 0.0;  ///< area of this mesh's load-tagged faces [m^2]
  LoadSpec load;            ///< the case's load (force_scale(t) ramps the traction)
  /// Step times t_n = n * dt, n = 1..steps [s]; the body starts undeformed at t = 0.
  std::vector<double> step_times;
  /// Smallest step a failed step may be cut back to (TimeSpec::minimum_step()) [s].
  double min_step = 0.0;

  double scale(double t) const { return load.force_scale(t); }
};

/// The case's loading programme on `mesh` (faces tagged fixed/load by the geometry pipeline). The patch area is
/// the mesh's own, so each model applies exactly the case's total force. Throws CaseError at /load/radius when
/// the mesh holds no load face.
LoadProgram load_program(const Case& c, const TetMesh& mesh);

}  // namespace core
