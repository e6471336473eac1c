#pragma once
// Quasi-static small-strain viscoelastic FEM (the reference model): FE_SimplexP<3>(degree)^3 on a
// simplex triangulation, the shared Kelvin law at every quadrature point (core::KelvinLaw, paper
// eqs. 9–13) and a full Newton solve of eq. 21 per time step with the consistent tangent.
//
// The verbs follow the deal.II tutorials (step-8/18/44): setup_system(), assemble_system(), solve(),
// output_results(), run(). Only reference_fem .cpp files include this header (deal.II is heavy).
#include <deal.II/base/timer.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>

#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/kelvin_law.hpp"
#include "reference_fem/point_history.hpp"
#include "reference_fem/problem.hpp"

namespace reference_fem {

class ViscoelasticSolver {
 public:
  /// The triangulation must outlive the solver. Call setup_system() before stepping.
  ViscoelasticSolver(const dealii::Triangulation<3>& triangulation, const SolverParameters& parameters,
                     BoundaryConditions conditions);

  /// Distribute DoFs, build the sparsity pattern, the homogeneous constraints and the history storage.
  void setup_system();

  /// Advance from the current time to t_new with Newton's method; commits the history on convergence. When
  /// Newton fails, the step is halved and retried down to parameters.newton.min_step (core/step_cutback.hpp).
  /// @throws core::InadmissibleStrain when a strain leaves the law's admissible range (at any iteration)
  /// @throws core::StepCutBackFailed when even the smallest step fails, with every attempt
  StepReport do_time_step(double t_new);

  /// Step through `times` (increasing, > current time), calling `on_step` after each converged step.
  void run(const std::vector<double>& times, const std::function<void(const StepReport&)>& on_step = {});

  /// Write the displacement (and the boundary ids as a cell field) to a VTU file.
  void output_results(const std::string& vtu_path) const;

  const dealii::DoFHandler<3>& dof_handler() const { return dof_handler_; }
  const dealii::Mapping<3>& mapping() const { return mapping_; }
  const dealii::Vector<double>& solution() const { return solution_; }
  const dealii::FESystem<3>& fe() const { return fe_; }
  double current_time() const { return time_; }
  /// The smallest 1 + 2k lambda over the converged steps so far, and where (docs/MATERIAL.md §1.5).
  const core::SmallestMargin& smallest_margin() const { return smallest_margin_; }
  /// Wall-clock totals of the TimerOutput sections (setup, assembly, solve, history, output).
  std::map<std::string, double> section_seconds() const;
  /// Volume averages of the converged stress (Voigt, tensor shears) and engineering strain at t_n.
  core::Vector6 average_stress() const;
  core::Vector6 average_strain() const;
  /// The strain within `radius` [m] of `centre` (the material under the probe) at t_n.
  BallStrain strain_in_ball(const Eigen::Vector3d& centre, double radius) const;
  /// Area of the faces with boundary id `id` [m^2] (on the straight-sided mesh).
  double boundary_area(unsigned int id) const;

 private:
  struct ScratchData;
  struct CopyData;

  /// Volume average of a per-point quantity of the converged history.
  core::Vector6 volume_average(const std::function<core::Vector6(const PointHistory&)>& field) const;
  /// Visit every quadrature point's converged history with its position and weight JxW.
  void for_each_quadrature_point(
      const std::function<void(const dealii::Point<3>&, double, const PointHistory&)>& visit) const;

  /// Assemble the tangent (eq. 21 with E_k of eq. 13) and the residual R = F_ext - F_int at the current
  /// solution, with the history of t_n and the step dt. Returns the residual norm (free rows only).
  double assemble_system(double t_new, double dt);
  void solve();
  void apply_dirichlet_values(double t_new);
  /// One Newton solve from the committed state to t_new: commits on convergence, restores the solution when
  /// it fails (the attempt of core::advance_with_cutback).
  core::NewtonAttempt newton_step(double t_new, StepReport* report);
  void update_history(double dt);
  void local_assemble(const typename dealii::DoFHandler<3>::active_cell_iterator& cell, ScratchData& scratch,
                      CopyData& copy) const;

  const dealii::Triangulation<3>& triangulation_;
  SolverParameters parameters_;
  BoundaryConditions conditions_;
  core::KelvinLaw law_;

  dealii::FESystem<3> fe_;
  dealii::MappingFE<3> mapping_;
  dealii::DoFHandler<3> dof_handler_;
  dealii::AffineConstraints<double> zero_constraints_;  // Newton updates vanish on Dirichlet rows
  dealii::SparsityPattern sparsity_pattern_;
  dealii::SparseMatrix<double> system_matrix_;
  dealii::Vector<double> solution_, newton_update_, system_rhs_;
  // LU factors (UMFPACK) of an earlier tangent: the preconditioner of the GMRES solves of the current
  // consistent tangent. Refactored when GMRES slows down, so Newton stays exact at a fraction of the cost.
  std::unique_ptr<dealii::SparseDirectUMFPACK> factorization_;
  bool refactor_ = true;
  int last_linear_iterations_ = 0;
  int factorizations_ = 0;
  std::vector<PointHistory> history_;  // active_cell_index * n_q + q
  unsigned int n_q_points_ = 0;
  double time_ = 0.0;
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
