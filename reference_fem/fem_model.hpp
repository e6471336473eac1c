#pragma once
// The FEM reference on a load case: what `tissue solve fem`, the tests and the mesh-convergence study
// call. deal.II-free header.
#include <Eigen/Core>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "reference_fem/problem.hpp"

namespace reference_fem {

struct FemRunOptions {
  /// When non-empty, write `<vtu_prefix>_NNNN.vtu` every `case.output.every` steps and at the last step.
  std::string vtu_prefix;
  double sample_tolerance = 3e-3;  ///< [m] how far a sample may lie outside the faceted mesh
  unsigned int threads = 2;
  std::function<void(const StepReport&)> on_step;  ///< progress callback after every converged step
  /// When not null, samples behind the crack front are evaluated on the lip core::RuledSurface::side gives them.
  const core::RuledSurface* cut = nullptr;
  /// When radius > 0, measure the strain within this ball at the last step (FemRunResult::probe_strain).
  Eigen::Vector3d probe_centre = Eigen::Vector3d::Zero();  ///< [m]
  double probe_radius = 0.0;                               ///< [m]
};

struct FemRunResult {
  Eigen::MatrixXd sample_displacements;  ///< #samples by 3 at the last step [m]
  std::vector<Eigen::MatrixXd> sample_history;  ///< per step, #samples by 3 [m]
  std::vector<double> sample_offsets;    ///< [m] distance of each sample outside the mesh
  std::vector<StepReport> steps;
  std::map<std::string, double> sections;  ///< TimerOutput totals [s]: setup, assembly, solve, ...
  double total_seconds = 0.0;
  std::size_t n_dofs = 0;
  std::size_t n_cells = 0;
  double load_area = 0.0;  ///< [m^2]
  int crack_faces = 0;     ///< boundary faces tagged FaceTag::crack (both sides of the cut)
  std::vector<std::string> vtu_files;
  Eigen::MatrixXd vertex_displacements;  ///< #mesh vertices by 3 at the last step [m]
  BallStrain probe_strain;  ///< strain within FemRunOptions::probe_radius of probe_centre at the last step
};

/// Solve on any tagged tet mesh (boundary ids = core::FaceTag values) with explicit conditions and
/// times (t_1 < t_2 < ..., starting from the undeformed state at t = 0; t_1 = 0 is an instantaneous step).
/// VTU files are written every `output_every` steps and at the last one when options.vtu_prefix is set.
FemRunResult solve_on_mesh(const core::TetMesh& mesh, const SolverParameters& parameters,
                           const BoundaryConditions& conditions, const std::vector<double>& times,
                           const Eigen::MatrixXd& sample_points, const FemRunOptions& options = {},
                           int output_every = 1);

/// Solve the case on geometry.fem_mesh: fixed faces clamped (strong Dirichlet), the load patch under a
/// uniform traction force(t)/area ramped by LoadSpec::force_scale, time steps of TimeSpec. The strain is
/// measured under the probe: within the load radius of the load centre (unless options say otherwise).
FemRunResult run_case(const core::Case& c, const core::Geometry& geometry, const FemRunOptions& options = {});

}  // namespace reference_fem
