#pragma once
// Quasi-static small-strain viscoelastic FEM (the reference model): FE_SimplexP<3>(degree)^3 on a
// simplex triangulation, the shared Kelvin law at every quadrature point (core::KelvinLaw, paper
// eqs. 9–13) and a full Newton solve of eq. 21 per time step with the consistent tangent.
//
// Distributed (step-40 style): on a parallel::fullydistributed::Triangulation each MPI process assembles
// its locally owned cells into Trilinos MPI matrices and vectors and keeps the quadrature-point history of
// those cells only; a serial Triangulation runs the same code on MPI_COMM_SELF. Every member function is
// collective over the triangulation's communicator unless it says otherwise.
//
// The verbs follow the deal.II tutorials (step-8/18/40/44): setup_system(), assemble_system(), solve(),
// output_results(), run(). Only reference_fem .cpp files include this header (deal.II is heavy).
#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/timer.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>
#include <deal.II/lac/vector.h>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/kelvin_law.hpp"
#include "reference_fem/point_history.hpp"
#include "reference_fem/problem.hpp"
#include "reference_fem/serial_matrix_copy.hpp"

class Epetra_MultiVector;

namespace reference_fem {

class ViscoelasticSolver {
 public:
  /// The triangulation must outlive the solver: a serial Triangulation<3> (solved on MPI_COMM_SELF) or a
  /// parallel one (solved on its communicator). Call setup_system() before stepping.
  /// Throws std::invalid_argument for the direct linear solver on more than one MPI process.
  ViscoelasticSolver(const dealii::Triangulation<3>& triangulation, const SolverParameters& parameters,
                     BoundaryConditions conditions);
  ~ViscoelasticSolver();

  /// Distribute DoFs, build the sparsity pattern, the homogeneous constraints, the rigid-body modes (AMG)
  /// and the history storage of the locally owned cells.
  void setup_system();

  /// Advance from the current time to t_new with Newton's method; commits the history on convergence. When
  /// Newton fails, the step is halved and retried down to parameters.newton.min_step (core/step_cutback.hpp).
  /// @throws core::InadmissibleStrain when a converged state leaves the law's admissible range, or when the
  ///         smallest step fails after meeting an iterate outside it (core/step_cutback.hpp)
  /// @throws core::StepCutBackFailed when even the smallest step fails, with every attempt
  StepReport do_time_step(double t_new);

  /// Step through `times` (increasing, > current time), calling `on_step` after each converged step.
  void run(const std::vector<double>& times, const std::function<void(const StepReport&)>& on_step = {});

  /// Apply the Dirichlet values of t_new and assemble the first Newton system of the step to t_new without
  /// solving it: system_matrix() du = system_rhs() (for studies of the linear solver).
  void assemble_newton_system(double t_new);
  const dealii::TrilinosWrappers::SparseMatrix& system_matrix() const { return system_matrix_; }
  const dealii::TrilinosWrappers::MPI::Vector& system_rhs() const { return system_rhs_; }

  /// Write the displacement (and the owning MPI rank as a cell field) as one VTU piece per process,
  /// `<directory>/<name>_<counter>.<rank>.vtu`, and the record `<name>_<counter>.pvtu` (rank 0) that
  /// ParaView opens. Returns the pvtu path.
  std::string output_results(const std::string& directory, const std::string& name, unsigned int counter) const;

  const dealii::DoFHandler<3>& dof_handler() const { return dof_handler_; }
  const dealii::Mapping<3>& mapping() const { return mapping_; }
  /// The displacement with the ghost entries of this process (read it on locally owned and ghost cells).
  const dealii::TrilinosWrappers::MPI::Vector& solution() const { return ghosted_solution_; }
  const dealii::FESystem<3>& fe() const { return fe_; }
  const dealii::IndexSet& locally_owned_dofs() const { return locally_owned_dofs_; }
  MPI_Comm mpi_communicator() const { return mpi_communicator_; }
  double current_time() const { return time_; }
  /// The smallest 1 + 2k lambda over the converged steps so far, and where, over all processes
  /// (docs/MATERIAL.md §1.5).
  const core::SmallestMargin& smallest_margin() const { return smallest_margin_; }
  /// Wall-clock totals of the TimerOutput sections (setup, assembly, solve, history, output) on this process.
  std::map<std::string, double> section_seconds() const;
  /// Volume averages of the converged stress (Voigt, tensor shears) and engineering strain at t_n.
  core::Vector6 average_stress() const;
  core::Vector6 average_strain() const;
  /// The strain within `radius` [m] of `centre` (the material under the probe) at t_n.
  BallStrain strain_in_ball(const Eigen::Vector3d& centre, double radius) const;
  /// The same measure over the quadrature points x [m] where inside(x) holds (e.g. a band around a region's edge).
  BallStrain strain_where(const std::function<bool(const Eigen::Vector3d&)>& inside) const;
  /// Area of the faces with boundary id `id` [m^2] (on the straight-sided mesh).
  double boundary_area(unsigned int id) const;

 private:
  struct ScratchData;
  struct CopyData;

  /// Volume average of a per-point quantity of the converged history.
  core::Vector6 volume_average(const std::function<core::Vector6(const PointHistory&)>& field) const;
  /// Visit every locally owned quadrature point's converged history with its position and weight JxW
  /// (the caller sums over the processes).
  void for_each_quadrature_point(
      const std::function<void(const dealii::Point<3>&, double, const PointHistory&)>& visit) const;

  /// Assemble the tangent (eq. 21 with E_k of eq. 13) and the residual R = F_ext - F_int at the current
  /// solution, with the history of t_n and the step dt. Returns the residual norm (free rows only). Without the
  /// tangent (`with_tangent` false) only the residual and the force norms are assembled, the same to the bit, and
  /// system_matrix() keeps the last tangent: for the assembly that only confirms convergence.
  double assemble_system(double t_new, double dt, bool with_tangent);
  /// Solve K du = R to eta ||R|| (GMRES) and update the solution.
  void solve(double eta);
  void apply_dirichlet_values(double t_new);
  /// One Newton solve from the committed state to t_new: commits on convergence, restores the solution when
  /// it fails (the attempt of core::advance_with_cutback). Starts from the extrapolated state when predict_start()
  /// allows, and from the committed state when that attempt fails.
  core::NewtonAttempt newton_step(double t_new, StepReport* report);
  /// Newton's iterations to t_new from the current solution; on failure restores `committed`.
  core::NewtonAttempt newton_iterations(double t_new, const dealii::TrilinosWrappers::MPI::Vector& committed,
                                        StepReport* report);
  /// Moves the solution to U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1}) when NewtonParameters::extrapolate_start is set, the
  /// last committed step ended at the current time and every boundary condition keeps its rate
  /// (core/step_predictor.hpp). Returns whether it did.
  bool predict_start(double t_new);
  bool conditions_keep_their_rate(double t_before, double t_from, double t_to) const;
  /// The last assembly's smallest margin as an error when it is outside the admissible range, else null.
  std::shared_ptr<const core::InadmissibleStrain> inadmissible_iterate(double t_new) const;
  void update_history(double dt);
  /// One cell's residual rows, and its tangent when `tangent` (assemble_system's with_tangent).
  void local_assemble(const typename dealii::DoFHandler<3>::active_cell_iterator& cell, ScratchData& scratch,
                      CopyData& copy, bool tangent) const;

  /// The preconditioner of the next GMRES solves, from the current tangent (LU factors or AMG hierarchy).
  void build_preconditioner();

  const dealii::Triangulation<3>& triangulation_;
  MPI_Comm mpi_communicator_;
  SolverParameters parameters_;
  BoundaryConditions conditions_;
  core::KelvinLaw law_;

  dealii::FESystem<3> fe_;
  dealii::MappingFE<3> mapping_;
  dealii::DoFHandler<3> dof_handler_;
  dealii::IndexSet locally_owned_dofs_, locally_relevant_dofs_;
  dealii::AffineConstraints<double> zero_constraints_;  // Newton updates vanish on Dirichlet rows
  dealii::TrilinosWrappers::SparseMatrix system_matrix_;
  dealii::TrilinosWrappers::MPI::Vector solution_;          // locally owned entries (written)
  dealii::TrilinosWrappers::MPI::Vector ghosted_solution_;  // owned + ghost entries (read by the cells)
  dealii::TrilinosWrappers::MPI::Vector newton_update_, system_rhs_;

  // Preconditioner of the GMRES solves of the current consistent tangent, built from an earlier tangent and
  // rebuilt when GMRES slows down, so Newton stays exact at a fraction of the cost.
  std::unique_ptr<dealii::TrilinosWrappers::PreconditionAMG> amg_;   // LinearSolverType::amg
  std::unique_ptr<Epetra_MultiVector> rigid_body_modes_;            // its near null space (6 columns)
  std::unique_ptr<dealii::SparseDirectUMFPACK> factorization_;     // LinearSolverType::direct: LU factors of serial_matrix_
  // One process: the tangent and the residual's vectors are assembled into deal.II objects, which add a cell's rows
  // faster than Epetra does, and copied into system_matrix_ and system_rhs_ after each assembly (serial_matrix_copy.hpp).
  // UMFPACK factorises serial_matrix_ itself.
  bool serial_ = false;
  dealii::SparsityPattern serial_pattern_;
  dealii::SparseMatrix<double> serial_matrix_;
  std::unique_ptr<SerialMatrixCopy> serial_copy_;
  dealii::Vector<double> serial_rhs_, serial_external_, serial_internal_;
  bool rebuild_ = true;
  int last_linear_iterations_ = 0;
  double last_linear_reduction_ = 1.0;  // ||K du - R|| / ||R|| that the last solve reached
  int preconditioner_builds_ = 0;

  std::vector<PointHistory> history_;  // active_cell_index * n_q + q, filled on locally owned cells only
  unsigned int n_q_points_ = 0;
  double time_ = 0.0;
  // The last committed step: its start U_{n-1} and times, for predict_start().
  struct PreviousStep {
    dealii::TrilinosWrappers::MPI::Vector start;
    double t_from = 0.0, t_to = 0.0;
  };
  std::optional<PreviousStep> previous_step_;
  double external_force_norm_ = 0.0;  // ||F_ext|| of the last assembly, the residual's scale
  double internal_force_norm_ = 0.0;  // ||F_int|| over all rows (reactions included)
  double step_time_ = 0.0;            // t_{n+1} and dt of the step being assembled (read by workers)
  double step_dt_ = 0.0;
  // The smallest 1 + 2k lambda of the last assembly and where (reduced over the cells by the copier).
  core::SmallestMargin iterate_margin_;
  core::SmallestMargin smallest_margin_;  // over the converged steps

  mutable std::ostringstream timer_sink_;
  mutable dealii::TimerOutput timer_;
};

}  // namespace reference_fem
