#pragma once
// The surrogate's training data (paper §3): the full meshless model (EfgModel) solved for many traction-patch
// loads on ONE node cloud, and the interpolated displacement u(X) = sum phi_i(X) U_i (eq. 7) recorded at
// every surface node at one time step. One set-up (MLS tables, sparsity) serves every load:
// EfgModel::restart().
//
// Threads: independent loads run on concurrent EfgModels (one per worker, each set up once), as many as the
// memory budget allows, measured on the first solve; each worker runs its OpenMP loops on its share of the
// cores.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "meshless/efg/efg_problem.hpp"
#include "meshless/surrogate/surrogate_load_patch.hpp"

namespace meshless {

/// One load of the full model: a uniform traction patch (load_patch()) around a surface node, carrying
/// `force` in total at full load and ramped by the problem's load_scale(t).
struct PatchLoad {
  int contact = -1;                                 ///< index into SurfaceNodes
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  ///< [N]
};

/// The full model's answer to one PatchLoad.
struct SolvedLoad {
  core::PointMatrix displacement;  ///< #S by 3 [m], u(X_s) at every surface node at the response step
  int newton_iterations = 0;       ///< over the steps solved
  double patch_area = 0.0;         ///< [m^2] the patch's area, or the smooth profile's integral over it
  double seconds = 0.0;            ///< wall time of the time stepping and the interpolation
};

struct PatchSolveOptions {
  double patch_radius = 0.01;  ///< [m]
  /// The traction over the patch: uniform on whole faces (load_patch()), or the smooth profile of
  /// smooth_load_patch(), whose response is continuous in the contact point (a contact region needs it).
  bool smooth_profile = false;
  int response_step = 1;       ///< 1-based step of problem.step_times at which the displacement is recorded
  /// Total memory the concurrent models may hold [bytes]. The first load is solved alone, and the growth of
  /// the peak resident memory it caused is taken as one model's footprint (tables, matrix and factorisation).
  double memory_budget_bytes = 4e9;
  int max_workers = 0;  ///< 0: the hardware threads
};

struct PatchSolveReport {
  int workers = 1;
  double model_bytes = 0.0;    ///< measured footprint of one model (see memory_budget_bytes)
  double setup_seconds = 0.0;  ///< of the first model (each further worker repeats it once)
  double wall_seconds = 0.0;   ///< everything, set-ups included
};

/// The first step whose load_scale reaches 1 (end of the ramp), or the last step (`at_end`). Throws
/// std::invalid_argument when the ramp never completes within the steps.
int response_step(const EfgProblem& problem, bool at_end);

/// Solve every load on `problem`'s cloud (its penalised faces, material, load_scale and steps; its own loads
/// are replaced). `progress` (may be empty) gets one line per solved load, from any worker, one call at a
/// time. Throws the first failure with the load's contact point and force.
std::vector<SolvedLoad> solve_patch_loads(const EfgProblem& problem, const EfgOptions& efg_options,
                                          const SurfaceNodes& surface, const std::vector<PatchLoad>& loads,
                                          const PatchSolveOptions& options,
                                          const std::function<void(const std::string&)>& progress = {},
                                          PatchSolveReport* report = nullptr);

/// The same force on the case's own load patch (the faces the geometry pipeline tagged `load`, imprinted into
/// the cloud) and on the training patch around a surface node (load_patch()), solved on the same cloud.
struct PatchComparison {
  double imprinted_area = 0.0, patch_area = 0.0;  ///< [m^2]
  int imprinted_faces = 0, patch_faces = 0;
  core::PointMatrix imprinted, patch;  ///< #S by 3 surface displacements [m] at the response step
};
PatchComparison compare_load_patches(const EfgProblem& problem, const EfgOptions& efg_options,
                                     const SurfaceNodes& surface, const PatchLoad& load,
                                     const PatchSolveOptions& options);

}  // namespace meshless
