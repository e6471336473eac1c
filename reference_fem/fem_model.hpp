#pragma once
// The FEM reference on a load case: what `tissue solve fem`, the tests and the mesh-convergence study
// call. deal.II-free header.
//
// MPI: the solve is collective over FemRunOptions::communicator. Every process passes the same mesh, case
// and options (core/geometry_broadcast.hpp sends rank 0's geometry); the mesh is partitioned, each
// process assembles and keeps the history of its own cells, and every process gets the same FemRunResult.
#include <mpi.h>

#include <Eigen/Core>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/inadmissible_strain.hpp"
#include "reference_fem/problem.hpp"

namespace reference_fem {

struct FemRunOptions {
  /// When non-empty, write `<vtu_prefix>_NNNN.pvtu` and its pieces `<vtu_prefix>_NNNN.<rank>.vtu` (one per
  /// MPI process) every `case.output.every` steps and at the last step.
  std::string vtu_prefix;
  double sample_tolerance = 3e-3;  ///< [m] how far a sample may lie outside the faceted mesh
  /// The processes that solve together: every process of the job (mpirun -np N), or MPI_COMM_SELF for a
  /// process that solves alone.
  MPI_Comm communicator = MPI_COMM_WORLD;
  /// Assembly threads per process; 0 keeps deal.II's choice (the node's cores shared among its processes).
  unsigned int threads = 0;
  std::function<void(const StepReport&)> on_step;  ///< progress callback after every converged step
  /// When not null, samples behind the crack front are evaluated on the lip core::RuledSurface::side gives them.
  const core::RuledSurface* cut = nullptr;
  /// run_case only: measure FemRunResult::support_edge_strain around this region's edge (null: none).
  const core::FixedRegionSpec* support_region = nullptr;
  /// When radius > 0, measure the strain within this ball at the last step (FemRunResult::probe_strain).
  Eigen::Vector3d probe_centre = Eigen::Vector3d::Zero();  ///< [m]
  double probe_radius = 0.0;                               ///< [m]
};

/// [m] half-width of the band around the fixed region's edge over which FemRunResult::support_edge_strain is taken.
constexpr double kSupportEdgeBand = 5e-3;

struct FemRunResult {
  Eigen::MatrixXd sample_displacements;  ///< #samples by 3 at the last step [m]
  std::vector<Eigen::MatrixXd> sample_history;  ///< per step, #samples by 3 [m]
  std::vector<double> sample_offsets;    ///< [m] distance of each sample outside the mesh
  std::vector<StepReport> steps;
  std::map<std::string, double> sections;  ///< TimerOutput totals [s]: setup, assembly, solve, ...
  double total_seconds = 0.0;
  double peak_memory_mb = 0.0;  ///< sum over the processes of their peak resident set size [MB]
  std::size_t n_dofs = 0;
  std::size_t n_cells = 0;
  double load_area = 0.0;  ///< [m^2]
  int crack_faces = 0;     ///< boundary faces tagged FaceTag::crack (both sides of the cut)
  std::vector<std::string> vtu_files;  ///< the pvtu records
  int mpi_processes = 1;
  std::vector<unsigned int> cells_per_process;  ///< locally owned cells of each process (the partition)
  Eigen::MatrixXd vertex_displacements;  ///< #mesh vertices by 3 at the last step [m]
  BallStrain probe_strain;  ///< strain within FemRunOptions::probe_radius of probe_centre at the last step
  /// run_case only: the strain within kSupportEdgeBand of the fixed region's edge (inside or out) at the last step,
  /// where a clamp's strain is singular; an elastic support's stays bounded under refinement (docs/MATERIAL.md §3).
  BallStrain support_edge_strain;
  core::SmallestMargin smallest_margin;  ///< smallest 1 + 2k lambda over the converged steps, and where
  double min_step = 0.0;    ///< [s] the smallest step a failed step could be cut back to (0: no cut-back)
};

/// Solve on any tagged tet mesh (boundary ids = core::FaceTag values) with explicit conditions and
/// times (t_1 < t_2 < ..., starting from the undeformed state at t = 0; t_1 = 0 is an instantaneous step).
/// VTU files are written every `output_every` steps and at the last one when options.vtu_prefix is set.
FemRunResult solve_on_mesh(const core::TetMesh& mesh, const SolverParameters& parameters,
                           const BoundaryConditions& conditions, const std::vector<double>& times,
                           const Eigen::MatrixXd& sample_points, const FemRunOptions& options = {},
                           int output_every = 1);

/// A case on its FEM mesh as a boundary-value problem: fixed faces clamped (strong Dirichlet), the load patch
/// under core::load_program's traction and ramp, its step times, and the case's discretisation and solvers.
struct CaseProblem {
  SolverParameters parameters;
  BoundaryConditions conditions;
  std::vector<double> times;
  double load_area = 0.0;  ///< [m^2]
};
CaseProblem problem_from_case(const core::Case& c, const core::TetMesh& mesh);

/// Solve the case on geometry.fem_mesh: fixed faces clamped (strong Dirichlet), the load patch under a
/// uniform traction force(t)/area ramped by LoadSpec::force_scale, time steps of TimeSpec. The strain is
/// measured under the probe: within the load radius of the load centre (unless options say otherwise).
FemRunResult run_case(const core::Case& c, const core::Geometry& geometry, const FemRunOptions& options = {});

}  // namespace reference_fem
