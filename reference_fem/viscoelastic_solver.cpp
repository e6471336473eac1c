#include "reference_fem/viscoelastic_solver.hpp"

#include <deal.II/base/multithread_info.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/work_stream.h>
#include <deal.II/distributed/tria_base.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/grid/filtered_iterator.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools.h>

#include <fmt/format.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/step_predictor.hpp"
#include "core/voigt.hpp"
#include "reference_fem/amg_preconditioner.hpp"

namespace reference_fem {
namespace {

using namespace dealii;

// Engineering Voigt strain [xx, yy, zz, 2xy, 2yz, 2zx] (core/voigt.hpp, the paper's operator L, eq. 17).
core::Vector6 to_voigt(const SymmetricTensor<2, 3>& e) {
  core::Vector6 v;
  v << e[0][0], e[1][1], e[2][2], 2.0 * e[0][1], 2.0 * e[1][2], 2.0 * e[2][0];
  return v;
}

// The smallest 1 + 2k lambda over all processes, with the time, point and strain of the process that holds it,
// so that every process sees the same margin and, past the admissible range, throws the same error.
core::SmallestMargin smallest_over_processes(const core::SmallestMargin& local, MPI_Comm comm) {
  if (Utilities::MPI::n_mpi_processes(comm) == 1) return local;
  const Utilities::MPI::MinMaxAvg extremes = Utilities::MPI::min_max_avg(local.margin, comm);
  std::array<double, 11> packed{};
  packed[0] = local.margin;
  packed[1] = local.time;
  for (int i = 0; i < 3; ++i) packed[2 + i] = local.point(i);
  for (int i = 0; i < 6; ++i) packed[5 + i] = local.strain(i);
  const int owner = static_cast<int>(extremes.min_index);
  const int status = MPI_Bcast(packed.data(), static_cast<int>(packed.size()), MPI_DOUBLE, owner, comm);
  AssertThrowMPI(status);
  core::SmallestMargin global;
  global.margin = packed[0];
  global.time = packed[1];
  for (int i = 0; i < 3; ++i) global.point(i) = packed[2 + i];
  for (int i = 0; i < 6; ++i) global.strain(i) = packed[5 + i];
  return global;
}

// Whether the Newton update just solved is expected to end the step, so that the next assembly only has to confirm
// it and needs no tangent. `relative`: the step's relative residuals r_0 .. r_k, the last one before the update;
// `linear_reduction`: the linear solve's ||K du - R|| / ||R||. The equations are linear (k = 0): the update leaves
// the linear solve's residual, linear_reduction r_k. Otherwise, once Newton contracts, its quadratic range gives
// r_{k+1} ~ C r_k^2 with C = r_k / r_{k-1}^2, plus what the inexact solve leaves. On the lung cases this estimate was
// 1.1-2 times the residual that followed (never below it), so a factor of 2 is kept in hand. A miss costs only the
// residual pass: the tangent of the same iterate is then assembled before the solve (newton_iterations).
bool update_ends_step(const std::vector<double>& relative, double linear_reduction, double tolerance, bool linear) {
  const double r = relative.back();
  double next = linear_reduction * r;
  if (!linear) {
    if (relative.size() < 2 || !(r < relative[relative.size() - 2])) return false;
    const double before = relative[relative.size() - 2];
    next = std::max(next, r * (r / before) * (r / before));
  }
  return std::isfinite(next) && 2.0 * next <= tolerance;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

MPI_Comm communicator_of(const Triangulation<3>& triangulation) {
  if (const auto* parallel = dynamic_cast<const parallel::TriangulationBase<3>*>(&triangulation))
    return parallel->get_communicator();
  return MPI_COMM_SELF;
}

using LocallyOwnedCell = FilteredIterator<typename DoFHandler<3>::active_cell_iterator>;

LocallyOwnedCell first_owned(const DoFHandler<3>& dof_handler) {
  return LocallyOwnedCell(IteratorFilters::LocallyOwnedCell(), dof_handler.begin_active());
}
LocallyOwnedCell end_owned(const DoFHandler<3>& dof_handler) {
  return LocallyOwnedCell(IteratorFilters::LocallyOwnedCell(), dof_handler.end());
}

/// UMFPACK factors (a serial dealii::Vector operator) as the preconditioner of GMRES on Trilinos vectors of
/// one process.
class UmfpackPreconditioner {
 public:
  explicit UmfpackPreconditioner(const SparseDirectUMFPACK& factors) : factors_(factors) {}
  void vmult(TrilinosWrappers::MPI::Vector& dst, const TrilinosWrappers::MPI::Vector& src) const {
    in_.reinit(src.size(), true);
    out_.reinit(src.size(), true);
    std::copy(src.begin(), src.end(), in_.begin());
    factors_.vmult(out_, in_);
    std::copy(out_.begin(), out_.end(), dst.begin());
  }

 private:
  const SparseDirectUMFPACK& factors_;
  mutable Vector<double> in_, out_;
};

ComponentMask mask_of(const std::array<bool, 3>& components) {
  return ComponentMask(std::vector<bool>(components.begin(), components.end()));
}

/// A DirichletCondition as a deal.II Function at time t.
class DirichletFunction : public Function<3> {
 public:
  DirichletFunction(const DirichletCondition& condition, double t) : Function<3>(3), condition_(condition), t_(t) {}
  void vector_value(const Point<3>& p, Vector<double>& values) const override {
    Eigen::Vector3d v;
    if (condition_.field)
      v = condition_.field(Eigen::Vector3d(p[0], p[1], p[2]), t_);
    else
      v = (condition_.scale ? condition_.scale(t_) : 1.0) * condition_.value;
    for (unsigned int c = 0; c < 3; ++c) values(c) = v(c);
  }
  double value(const Point<3>& p, const unsigned int component) const override {
    Vector<double> v(3);
    vector_value(p, v);
    return v(component);
  }

 private:
  const DirichletCondition& condition_;
  double t_;
};

}  // namespace

// Per-thread work space of the WorkStream assembly (copyable: WorkStream clones it per thread).
struct ViscoelasticSolver::ScratchData {
  ScratchData(const Mapping<3>& mapping, const FiniteElement<3>& fe, const Quadrature<3>& quadrature,
              const Quadrature<2>& face_quadrature)
      : fe_values(mapping, fe, quadrature, update_gradients | update_JxW_values | update_quadrature_points),
        fe_face_values(mapping, fe, face_quadrature, update_values | update_quadrature_points | update_JxW_values),
        strains(quadrature.size()),
        B(6 * quadrature.size(), fe.n_dofs_per_cell()),
        DB(6 * quadrature.size(), fe.n_dofs_per_cell()) {}
  ScratchData(const ScratchData& other)
      : fe_values(other.fe_values.get_mapping(), other.fe_values.get_fe(), other.fe_values.get_quadrature(),
                  other.fe_values.get_update_flags()),
        fe_face_values(other.fe_face_values.get_mapping(), other.fe_face_values.get_fe(),
                       other.fe_face_values.get_quadrature(), other.fe_face_values.get_update_flags()),
        strains(other.strains.size()),
        B(other.B.rows(), other.B.cols()),
        DB(other.DB.rows(), other.DB.cols()) {}

  FEValues<3> fe_values;
  FEFaceValues<3> fe_face_values;
  std::vector<SymmetricTensor<2, 3>> strains;
  std::vector<Tensor<1, 3>> face_displacements;  // u at the face quadrature points of an elastic support
  Eigen::MatrixXd B, DB;  // the B_q and D_q B_q JxW_q of all quadrature points, stacked (6 n_q by n)
  Eigen::MatrixXd K;
};

struct ViscoelasticSolver::CopyData {
  FullMatrix<double> cell_matrix;
  Vector<double> cell_rhs;
  Vector<double> cell_external;
  Vector<double> cell_internal;
  std::vector<types::global_dof_index> local_dof_indices;
  core::SmallestMargin margin;  // the cell's smallest 1 + 2k lambda and where
};

ViscoelasticSolver::ViscoelasticSolver(const Triangulation<3>& triangulation, const SolverParameters& parameters,
                                       BoundaryConditions conditions)
    : triangulation_(triangulation),
      mpi_communicator_(communicator_of(triangulation)),
      parameters_(parameters),
      conditions_(std::move(conditions)),
      law_(parameters.material),
      fe_(FE_SimplexP<3>(static_cast<unsigned int>(parameters.degree)), 3),
      mapping_(FE_SimplexP<3>(1)),
      dof_handler_(triangulation),
      timer_(timer_sink_, TimerOutput::never, TimerOutput::wall_times) {
  if (parameters.degree < 1 || parameters.degree > 3)
    throw std::invalid_argument("ViscoelasticSolver: degree must be 1, 2 or 3");
  if (parameters.newton.linear.type == LinearSolverType::direct &&
      Utilities::MPI::n_mpi_processes(mpi_communicator_) > 1)
    throw std::invalid_argument(
        "ViscoelasticSolver: the direct linear solver (UMFPACK) runs on one MPI process; set /fem/linear_solver "
        "to \"amg\" to solve on " + std::to_string(Utilities::MPI::n_mpi_processes(mpi_communicator_)) +
        " processes");
  if (parameters.threads > 0) MultithreadInfo::set_thread_limit(parameters.threads);
}

ViscoelasticSolver::~ViscoelasticSolver() = default;

void ViscoelasticSolver::setup_system() {
  TimerOutput::Scope scope(timer_, "setup");
  dof_handler_.distribute_dofs(fe_);
  locally_owned_dofs_ = dof_handler_.locally_owned_dofs();
  DoFTools::extract_locally_relevant_dofs(dof_handler_, locally_relevant_dofs_);

  zero_constraints_.clear();
  zero_constraints_.reinit(locally_relevant_dofs_);
  for (const auto& d : conditions_.dirichlet)
    VectorTools::interpolate_boundary_values(mapping_, dof_handler_, d.boundary_id, Functions::ZeroFunction<3>(3),
                                             zero_constraints_, mask_of(d.components));
  zero_constraints_.close();

  DynamicSparsityPattern dsp(locally_relevant_dofs_);
  DoFTools::make_sparsity_pattern(dof_handler_, dsp, zero_constraints_, false);
  SparsityTools::distribute_sparsity_pattern(dsp, locally_owned_dofs_, mpi_communicator_, locally_relevant_dofs_);
  system_matrix_.reinit(locally_owned_dofs_, locally_owned_dofs_, dsp, mpi_communicator_);
  solution_.reinit(locally_owned_dofs_, mpi_communicator_);
  ghosted_solution_.reinit(locally_owned_dofs_, locally_relevant_dofs_, mpi_communicator_);
  newton_update_.reinit(locally_owned_dofs_, mpi_communicator_);
  system_rhs_.reinit(locally_owned_dofs_, mpi_communicator_);

  amg_.reset();
  factorization_.reset();
  rebuild_ = true;
  serial_ = Utilities::MPI::n_mpi_processes(mpi_communicator_) == 1;
  serial_copy_.reset();
  if (serial_) {
    serial_pattern_.copy_from(dsp);  // one process: the whole pattern
    serial_matrix_.reinit(serial_pattern_);
    serial_copy_ = std::make_unique<SerialMatrixCopy>(serial_pattern_, system_matrix_);
    serial_rhs_.reinit(dof_handler_.n_dofs());
    serial_external_.reinit(dof_handler_.n_dofs());
    serial_internal_.reinit(dof_handler_.n_dofs());
  }
  if (parameters_.newton.linear.type != LinearSolverType::direct)
    rigid_body_modes_ = rigid_body_modes(dof_handler_, mapping_, locally_owned_dofs_,
                                         system_matrix_.trilinos_matrix().DomainMap());

  n_q_points_ = QGaussSimplex<3>(static_cast<unsigned int>(parameters_.degree + 1)).size();
  history_.assign(static_cast<std::size_t>(triangulation_.n_active_cells()) * n_q_points_, PointHistory{});
  time_ = 0.0;
}

void ViscoelasticSolver::apply_dirichlet_values(double t_new) {
  // Start Newton from a displacement that already satisfies u = g(t_{n+1}) on the Dirichlet rows; the
  // updates then obey the homogeneous constraints.
  AffineConstraints<double> values;
  values.reinit(locally_relevant_dofs_);
  for (const auto& d : conditions_.dirichlet) {
    VectorTools::interpolate_boundary_values(mapping_, dof_handler_, d.boundary_id, DirichletFunction(d, t_new), values,
                                             mask_of(d.components));
  }
  values.close();
  values.distribute(solution_);
  ghosted_solution_ = solution_;
}

void ViscoelasticSolver::local_assemble(const typename DoFHandler<3>::active_cell_iterator& cell,
                                        ScratchData& scratch, CopyData& copy, bool tangent) const {
  const unsigned int n = fe_.n_dofs_per_cell();
  if (tangent) copy.cell_matrix.reinit(n, n);
  copy.cell_rhs.reinit(n);
  copy.cell_external.reinit(n);
  copy.cell_internal.reinit(n);
  copy.local_dof_indices.resize(n);
  cell->get_dof_indices(copy.local_dof_indices);

  const FEValuesExtractors::Vector u(0);
  scratch.fe_values.reinit(cell);
  scratch.fe_values[u].get_function_symmetric_gradients(ghosted_solution_, scratch.strains);

  // B_q columns: engineering Voigt strain of each shape function at point q, so that
  // K = sum_q B_q^T D_q B_q JxW_q (eq. 21) with D = E_k dN/deps, the consistent tangent of eq. 13
  // (non-symmetric when k != 0). Stacked over q, K is one product B^T (DB): one large GEMM instead of n_q
  // small ones.
  Eigen::MatrixXd& B = scratch.B;
  Eigen::MatrixXd& DB = scratch.DB;
  Eigen::VectorXd internal = Eigen::VectorXd::Zero(n);
  const std::size_t first = cell->active_cell_index() * n_q_points_;
  copy.margin = core::SmallestMargin{};
  for (unsigned int q = 0; q < n_q_points_; ++q) {
    const core::Vector6 strain = to_voigt(scratch.strains[q]);
    if (law_.parameters().k != 0.0) {  // the law's admissible range (docs/MATERIAL.md §1.5)
      const Point<3>& x = scratch.fe_values.quadrature_point(q);
      copy.margin.update(law_.admissibility_margin(strain), step_time_, Eigen::Vector3d(x[0], x[1], x[2]), strain);
    }
    const auto Bq = B.middleRows<6>(6 * q);
    for (unsigned int i = 0; i < n; ++i) B.block<6, 1>(6 * q, i) = to_voigt(scratch.fe_values[u].symmetric_gradient(i, q));
    const double jxw = scratch.fe_values.JxW(q);
    if (tangent) {
      const core::KelvinResponse response = law_.update(history_[first + q].state, strain, step_dt_);
      DB.middleRows<6>(6 * q).noalias() = (response.tangent * jxw) * Bq;
      internal.noalias() += Bq.transpose() * (response.stress * jxw);
    } else {  // the same stress, bit for bit (KelvinLaw::updated_stress), without the tangent's work
      internal.noalias() += Bq.transpose() * (law_.updated_stress(history_[first + q].state, strain, step_dt_) * jxw);
    }
  }
  if (tangent) scratch.K.noalias() = B.transpose() * DB;
  for (unsigned int i = 0; i < n; ++i) {
    copy.cell_rhs(i) = -internal(i);
    copy.cell_internal(i) = internal(i);
    if (tangent)
      for (unsigned int j = 0; j < n; ++j) copy.cell_matrix(i, j) = scratch.K(i, j);
  }

  for (const auto f : cell->face_indices()) {
    if (!cell->face(f)->at_boundary()) continue;
    // Elastic supports: t = -k_s(x) u, a term of the internal force and of the tangent (k_s phi_i . phi_j).
    for (const auto& support : conditions_.supports) {
      if (cell->face(f)->boundary_id() != support.boundary_id) continue;
      scratch.fe_face_values.reinit(cell, f);
      const unsigned int n_face_q = scratch.fe_face_values.n_quadrature_points;
      scratch.face_displacements.resize(n_face_q);
      scratch.fe_face_values[u].get_function_values(ghosted_solution_, scratch.face_displacements);
      for (unsigned int q = 0; q < n_face_q; ++q) {
        const Point<3>& x = scratch.fe_face_values.quadrature_point(q);
        const double ks_jxw = support.stiffness(Eigen::Vector3d(x[0], x[1], x[2])) * scratch.fe_face_values.JxW(q);
        if (ks_jxw == 0.0) continue;
        for (unsigned int i = 0; i < n; ++i) {
          const Tensor<1, 3> phi_i = scratch.fe_face_values[u].value(i, q);
          const double force = ks_jxw * (phi_i * scratch.face_displacements[q]);
          copy.cell_rhs(i) -= force;
          copy.cell_internal(i) += force;
          if (tangent)
            for (unsigned int j = 0; j < n; ++j)
              copy.cell_matrix(i, j) += ks_jxw * (phi_i * scratch.fe_face_values[u].value(j, q));
        }
      }
    }
    // Uniform tractions (the load patch: force(t) / patch area).
    for (const auto& t : conditions_.tractions) {
      if (cell->face(f)->boundary_id() != t.boundary_id) continue;
      const double s = t.scale ? t.scale(step_time_) : 1.0;
      Tensor<1, 3> traction;
      for (unsigned int c = 0; c < 3; ++c) traction[c] = s * t.traction(c);
      scratch.fe_face_values.reinit(cell, f);
      for (unsigned int q = 0; q < scratch.fe_face_values.n_quadrature_points; ++q)
        for (unsigned int i = 0; i < n; ++i) {
          if (t.field) {
            const Point<3>& x = scratch.fe_face_values.quadrature_point(q);
            const Eigen::Vector3d v = t.field(Eigen::Vector3d(x[0], x[1], x[2]), step_time_);
            for (unsigned int c = 0; c < 3; ++c) traction[c] = v(c);
          }
          const double v = scratch.fe_face_values[u].value(i, q) * traction * scratch.fe_face_values.JxW(q);
          copy.cell_rhs(i) += v;
          copy.cell_external(i) += v;
        }
    }
  }
}

double ViscoelasticSolver::assemble_system(double t_new, double dt, bool with_tangent) {
  TimerOutput::Scope scope(timer_, "assembly");
  step_time_ = t_new;
  step_dt_ = dt;
  const unsigned int degree = static_cast<unsigned int>(parameters_.degree);
  ScratchData scratch(mapping_, fe_, QGaussSimplex<3>(degree + 1), QGaussSimplex<2>(degree + 1));
  iterate_margin_ = core::SmallestMargin{};
  const auto local = [this, with_tangent](const typename DoFHandler<3>::active_cell_iterator& cell, ScratchData& s,
                                          CopyData& c) { local_assemble(cell, s, c, with_tangent); };
  // WorkStream's serial stage: one cell's rows into the global objects (deal.II's on one process, Trilinos's else).
  const auto add_cell = [this, with_tangent](const CopyData& c, auto& matrix, auto& rhs, auto& external,
                                             auto& internal) {
    iterate_margin_.update(c.margin.margin, c.margin.time, c.margin.point, c.margin.strain);
    internal.add(c.local_dof_indices, c.cell_internal);  // all rows: includes the reactions
    // The constraints are homogeneous, so both calls leave the constrained rows of rhs at zero and add the free
    // rows alike: a residual-only assembly gives the residual of the full one.
    if (with_tangent)
      zero_constraints_.distribute_local_to_global(c.cell_matrix, c.cell_rhs, c.local_dof_indices, matrix, rhs);
    else
      zero_constraints_.distribute_local_to_global(c.cell_rhs, c.local_dof_indices, rhs);
    zero_constraints_.distribute_local_to_global(c.cell_external, c.local_dof_indices, external);
  };
  if (serial_) {
    if (with_tangent) serial_matrix_ = 0.0;
    serial_rhs_ = 0.0;
    serial_external_ = 0.0;
    serial_internal_ = 0.0;
    WorkStream::run(
        first_owned(dof_handler_), end_owned(dof_handler_), local,  // one process: every cell
        [&](const CopyData& c) { add_cell(c, serial_matrix_, serial_rhs_, serial_external_, serial_internal_); },
        scratch, CopyData());
    if (with_tangent) serial_copy_->copy(serial_matrix_, &system_matrix_);
    for (types::global_dof_index i = 0; i < serial_rhs_.size(); ++i) system_rhs_[i] = serial_rhs_(i);
    system_rhs_.compress(VectorOperation::insert);
    external_force_norm_ = serial_external_.l2_norm();
    internal_force_norm_ = serial_internal_.l2_norm();
  } else {
    if (with_tangent) system_matrix_ = 0.0;
    system_rhs_ = 0.0;
    TrilinosWrappers::MPI::Vector external(locally_owned_dofs_, mpi_communicator_);
    TrilinosWrappers::MPI::Vector internal(locally_owned_dofs_, mpi_communicator_);
    // Locally owned cells only; rows owned by another process are sent to it by compress().
    WorkStream::run(
        first_owned(dof_handler_), end_owned(dof_handler_), local,
        [&](const CopyData& c) { add_cell(c, system_matrix_, system_rhs_, external, internal); }, scratch,
        CopyData());
    if (with_tangent) system_matrix_.compress(VectorOperation::add);  // the same choice on every process
    system_rhs_.compress(VectorOperation::add);
    external.compress(VectorOperation::add);
    internal.compress(VectorOperation::add);
    external_force_norm_ = external.l2_norm();
    internal_force_norm_ = internal.l2_norm();
  }
  // The same on every process; newton_step() decides what a point past the admissible range means.
  iterate_margin_ = smallest_over_processes(iterate_margin_, mpi_communicator_);
  return system_rhs_.l2_norm();
}

void ViscoelasticSolver::build_preconditioner() {
  ++preconditioner_builds_;
  rebuild_ = false;
  if (parameters_.newton.linear.type == LinearSolverType::direct) {
    factorization_ = std::make_unique<SparseDirectUMFPACK>();
    factorization_->initialize(serial_matrix_);  // the direct solver runs on one process only (constructor)
    return;
  }
  AmgOptions options;
  options.higher_order_elements = parameters_.degree > 1;
  amg_ = std::make_unique<TrilinosWrappers::PreconditionAMG>();
  amg_->initialize(system_matrix_, ml_parameters(system_matrix_, *rigid_body_modes_, options));
}

void ViscoelasticSolver::solve(double eta) {
  TimerOutput::Scope scope(timer_, "solve");
  // The consistent tangent is non-symmetric for k != 0 (docs/MATERIAL.md §1.4), so: GMRES on the exact
  // tangent, right-preconditioned (it measures the true residual) by a preconditioner of an earlier tangent.
  // The tangent changes only through dN/deps (a few per cent for tissue strains), so the costly
  // preconditioner (LU factors or AMG hierarchy) is reused over Newton iterations and time steps, and
  // rebuilt when GMRES slows down.
  const LinearSolverParameters& linear = parameters_.newton.linear;
  if (rebuild_ || (!amg_ && !factorization_)) build_preconditioner();
  const double rhs_norm = system_rhs_.l2_norm();
  const double target = eta * rhs_norm;
  int iterations = 0;
  double reached = rhs_norm;
  const auto run_gmres = [&] {
    newton_update_ = 0.0;
    SolverControl control(static_cast<unsigned int>(linear.max_iterations), target, false, false);
    SolverGMRES<TrilinosWrappers::MPI::Vector> gmres(control,
                                                    SolverGMRES<TrilinosWrappers::MPI::Vector>::AdditionalData(62, true));
    try {
      if (amg_)
        gmres.solve(system_matrix_, newton_update_, system_rhs_, *amg_);
      else
        gmres.solve(system_matrix_, newton_update_, system_rhs_, UmfpackPreconditioner(*factorization_));
      iterations += static_cast<int>(control.last_step());
      reached = control.last_value();
      return true;
    } catch (const SolverControl::NoConvergence&) {
      iterations += static_cast<int>(control.last_step());
      return false;
    }
  };
  if (!run_gmres()) {
    build_preconditioner();  // the stored preconditioner went stale: rebuild it from this tangent
    last_linear_iterations_ = iterations;
    if (!run_gmres())
      throw std::runtime_error(fmt::format(
          "ViscoelasticSolver: GMRES ({} preconditioner, rebuilt from the current tangent) did not reduce the Newton "
          "residual by {:.0e} within {} iterations at t = {} s. The tangent may be close to singular (a strain near "
          "dN/deps = 0, docs/MATERIAL.md §1.4: reduce the load or refine the mesh under it); on a small mesh, "
          "/fem/linear_solver \"direct\" solves it exactly",
          linear.type == LinearSolverType::amg ? "AMG" : "LU", eta, linear.max_iterations, step_time_));
  }
  last_linear_iterations_ = iterations;
  last_linear_reduction_ = reached / rhs_norm;
  const double decades = std::max(1.0, std::log10(rhs_norm / std::max(reached, 1e-300 * rhs_norm)));
  if (iterations > linear.rebuild_after * decades) rebuild_ = true;
  zero_constraints_.distribute(newton_update_);
  solution_ += newton_update_;
  ghosted_solution_ = solution_;
}

void ViscoelasticSolver::update_history(double dt) {
  TimerOutput::Scope scope(timer_, "history");
  const unsigned int degree = static_cast<unsigned int>(parameters_.degree);
  FEValues<3> fe_values(mapping_, fe_, QGaussSimplex<3>(degree + 1), update_gradients);
  std::vector<SymmetricTensor<2, 3>> strains(n_q_points_);
  const FEValuesExtractors::Vector u(0);
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fe_values.reinit(cell);
    fe_values[u].get_function_symmetric_gradients(ghosted_solution_, strains);
    const std::size_t first = cell->active_cell_index() * n_q_points_;
    for (unsigned int q = 0; q < n_q_points_; ++q) {
      const core::KelvinState old_state = history_[first + q].state;
      law_.update(old_state, to_voigt(strains[q]), dt, &history_[first + q].state);
    }
  }
}

StepReport ViscoelasticSolver::do_time_step(double t_new) {
  const auto start = std::chrono::steady_clock::now();
  if (!(t_new - time_ >= 0.0)) throw std::invalid_argument("ViscoelasticSolver: time steps must not go backwards");
  StepReport report;
  report.time = t_new;
  // One Newton solve over the whole step; halved sub-steps only when it fails.
  const core::CutBackRecord cut =
      core::advance_with_cutback("FEM reference", time_, t_new, parameters_.newton.min_step,
                                 [&](double, double t_to) { return newton_step(t_to, &report); });
  report.substeps = cut.substeps;
  report.failed_attempts = cut.failures;
  report.wall_seconds = seconds_since(start);
  return report;
}

core::NewtonAttempt ViscoelasticSolver::newton_step(double t_new, StepReport* report) {
  TrilinosWrappers::MPI::Vector committed = solution_;  // restored when an attempt fails; then the step's start
  const bool predicted = predict_start(t_new);
  core::NewtonAttempt attempt = newton_iterations(t_new, committed, report);
  if (!attempt.converged() && predicted) {
    // The start from the committed state is the fallback: the predictor changes the path, never the equilibrium, so
    // a failure it caused must not cost a halved step. The failed attempt is kept in the report.
    attempt.failure = "from the extrapolated start (NewtonParameters::extrapolate_start): " + attempt.failure;
    report->retried_plain.push_back(attempt);
    attempt = newton_iterations(t_new, committed, report);
  }
  if (!attempt.converged()) return attempt;
  // A converged state past the range is no equilibrium of the law: no step size helps, stop the run.
  if (auto outside = inadmissible_iterate(t_new)) {
    solution_ = committed;
    ghosted_solution_ = solution_;
    throw core::InadmissibleStrain(*outside);
  }
  attempt.inadmissible = nullptr;
  report->residuals = attempt.residuals;
  report->admissibility_margin = std::min(report->admissibility_margin, iterate_margin_.margin);
  smallest_margin_.update(iterate_margin_.margin, t_new, iterate_margin_.point, iterate_margin_.strain);
  update_history(t_new - time_);
  previous_step_ = PreviousStep{std::move(committed), time_, t_new};  // the predictor's U_{n-1}, moved, not copied
  time_ = t_new;
  return attempt;
}

bool ViscoelasticSolver::conditions_keep_their_rate(double t_before, double t_from, double t_to) const {
  // A field's time dependence is not known here (the cantilever verification's): no prediction with one.
  for (const auto& d : conditions_.dirichlet)
    if (d.field || !core::load_keeps_its_rate(d.scale, t_before, t_from, t_to)) return false;
  for (const auto& t : conditions_.tractions)
    if (t.field || !core::load_keeps_its_rate(t.scale, t_before, t_from, t_to)) return false;
  return true;  // the elastic supports do not depend on time
}

bool ViscoelasticSolver::predict_start(double t_new) {
  if (!parameters_.newton.extrapolate_start || !previous_step_) return false;
  const PreviousStep& p = *previous_step_;
  const double dt_before = p.t_to - p.t_from, dt = t_new - time_;
  if (!(dt_before > 0.0) || std::abs(p.t_to - time_) > 1e-9 * dt_before) return false;  // not the step before
  if (!conditions_keep_their_rate(p.t_from, time_, t_new)) return false;
  TrilinosWrappers::MPI::Vector increment = solution_;
  increment -= p.start;
  solution_.add(dt / dt_before, increment);  // U_{n+1} ~ U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1})
  ghosted_solution_ = solution_;
  return true;
}

core::NewtonAttempt ViscoelasticSolver::newton_iterations(double t_new, const TrilinosWrappers::MPI::Vector& committed,
                                                          StepReport* report) {
  const double dt = t_new - time_;
  core::NewtonAttempt attempt;
  attempt.t_start = time_;
  attempt.t_end = t_new;
  apply_dirichlet_values(t_new);

  const core::DivergenceTest diverging;
  double reference = 0.0;
  bool with_tangent = true;  // false when the update just made is predicted to end the step (update_ends_step)
  for (int iteration = 0;; ++iteration) {
    const auto t_assembly = std::chrono::steady_clock::now();
    const double norm = assemble_system(t_new, dt, with_tangent);
    ++(with_tangent ? report->tangent_assemblies : report->residual_only_assemblies);
    report->assembly_seconds += seconds_since(t_assembly);
    // Relative residual: scaled by the largest of the first residual of the step, the external load and
    // the internal force (reactions included), so that a step that barely changes (relaxation or creep
    // under a held load) is measured against the forces in the body, not against round-off.
    if (iteration == 0) reference = std::max({norm, external_force_norm_, internal_force_norm_});
    const double relative = reference > 0.0 ? norm / reference : 0.0;
    // A transient iterate past the admissible range is remembered, not fatal: if Newton fails, the first such
    // iterate is reported (later iterates of a failing attempt drifted further off on the lung-tip case).
    if (!attempt.inadmissible) attempt.inadmissible = inadmissible_iterate(t_new);
    attempt.residuals.push_back(std::isfinite(norm) ? relative : norm);
    attempt.failure = diverging(attempt.residuals);
    if (!attempt.converged()) break;
    if (relative <= parameters_.newton.tolerance) break;
    if (iteration >= parameters_.newton.max_iterations) {
      attempt.failure = "the iteration limit (max_newton_iterations) was reached";
      break;
    }
    if (!with_tangent) {  // the prediction missed: this iterate's tangent is needed after all (same residual)
      const auto t_tangent = std::chrono::steady_clock::now();
      assemble_system(t_new, dt, true);
      ++report->tangent_assemblies;
      report->assembly_seconds += seconds_since(t_tangent);
    }
    const auto t_solve = std::chrono::steady_clock::now();
    const int builds_before = preconditioner_builds_;
    // Inexact Newton for the nonlinear law only: with k = 0 the equations are linear, and one solve to the
    // linear tolerance ends the step.
    const LinearSolverParameters& linear = parameters_.newton.linear;
    const double forcing = parameters_.material.k == 0.0 ? 0.0 : linear.forcing;
    try {
      solve(std::max(linear.tolerance, std::min(0.1, forcing * relative)));
    } catch (const std::exception& e) {  // GMRES failed with a fresh preconditioner: a near-singular tangent
      attempt.failure = std::string("the linear solve failed: ") + e.what();
      break;
    }
    if (!std::isfinite(newton_update_.l2_norm())) {
      attempt.failure = "the linear solve gave a non-finite update";
      break;
    }
    report->solve_seconds += seconds_since(t_solve);
    report->linear_iterations += last_linear_iterations_;
    report->preconditioner_builds += preconditioner_builds_ - builds_before;
    ++report->newton_iterations;
    ++attempt.iterations;
    with_tangent = !(parameters_.newton.confirm_without_tangent &&
                     update_ends_step(attempt.residuals, last_linear_reduction_, parameters_.newton.tolerance,
                                      parameters_.material.k == 0.0));
  }
  if (!attempt.converged()) {
    solution_ = committed;
    ghosted_solution_ = solution_;
    rebuild_ = true;  // the preconditioner belongs to a failed iterate
  }
  return attempt;
}

std::shared_ptr<const core::InadmissibleStrain> ViscoelasticSolver::inadmissible_iterate(double t_new) const {
  if (law_.admits(iterate_margin_.margin)) return nullptr;
  return std::make_shared<const core::InadmissibleStrain>("FEM reference", t_new, iterate_margin_.point,
                                                          iterate_margin_.strain, law_);
}

void ViscoelasticSolver::assemble_newton_system(double t_new) {
  apply_dirichlet_values(t_new);
  assemble_system(t_new, t_new - time_, true);
}

void ViscoelasticSolver::run(const std::vector<double>& times, const std::function<void(const StepReport&)>& on_step) {
  int step = 0;
  for (const double t : times) {
    StepReport report = do_time_step(t);
    report.step = ++step;
    if (on_step) on_step(report);
  }
}

std::string ViscoelasticSolver::output_results(const std::string& directory, const std::string& name,
                                               unsigned int counter) const {
  TimerOutput::Scope scope(timer_, "output");
  DataOut<3> data_out;
  data_out.attach_dof_handler(dof_handler_);
  const std::vector<std::string> names(3, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> interpretation(
      3, DataComponentInterpretation::component_is_part_of_vector);
  data_out.add_data_vector(ghosted_solution_, names, DataOut<3>::type_dof_data, interpretation);
  Vector<float> rank(triangulation_.n_active_cells());
  rank = static_cast<float>(Utilities::MPI::this_mpi_process(mpi_communicator_));
  data_out.add_data_vector(rank, "mpi_rank");
  data_out.build_patches(mapping_, static_cast<unsigned int>(parameters_.degree));  // locally owned cells
  // Every process writes its piece; a failed write anywhere fails the call on every process (collectively, so
  // no process is left waiting for the others).
  std::string record;
  bool written = true;
  try {
    record = data_out.write_vtu_with_pvtu_record(directory + "/", name, counter, mpi_communicator_, 4, 0);
  } catch (const std::exception&) {
    written = false;
  }
  if (Utilities::MPI::min(written ? 1 : 0, mpi_communicator_) == 0)
    throw std::runtime_error(fmt::format("ViscoelasticSolver: cannot write the VTU files {}/{}_{:04d}.*", directory,
                                         name, counter));
  return directory + "/" + record;
}

std::map<std::string, double> ViscoelasticSolver::section_seconds() const {
  return timer_.get_summary_data(TimerOutput::total_wall_time);
}

void ViscoelasticSolver::for_each_quadrature_point(
    const std::function<void(const Point<3>&, double, const PointHistory&)>& visit) const {
  const unsigned int degree = static_cast<unsigned int>(parameters_.degree);
  FEValues<3> fe_values(mapping_, fe_, QGaussSimplex<3>(degree + 1), update_JxW_values | update_quadrature_points);
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fe_values.reinit(cell);
    const std::size_t first = cell->active_cell_index() * n_q_points_;
    for (unsigned int q = 0; q < n_q_points_; ++q)
      visit(fe_values.quadrature_point(q), fe_values.JxW(q), history_[first + q]);
  }
}

core::Vector6 ViscoelasticSolver::volume_average(
    const std::function<core::Vector6(const PointHistory&)>& field) const {
  core::Vector6 sum = core::Vector6::Zero();
  double volume = 0.0;
  for_each_quadrature_point([&](const Point<3>&, double jxw, const PointHistory& h) {
    sum += field(h) * jxw;
    volume += jxw;
  });
  Utilities::MPI::sum(ArrayView<const double>(sum.data(), 6), mpi_communicator_, ArrayView<double>(sum.data(), 6));
  return sum / Utilities::MPI::sum(volume, mpi_communicator_);
}

core::Vector6 ViscoelasticSolver::average_stress() const {
  return volume_average([](const PointHistory& h) { return h.state.stress; });
}

core::Vector6 ViscoelasticSolver::average_strain() const {
  return volume_average([](const PointHistory& h) { return h.state.strain; });
}

BallStrain ViscoelasticSolver::strain_in_ball(const Eigen::Vector3d& centre, double radius) const {
  return strain_where([&](const Eigen::Vector3d& x) { return (x - centre).norm() <= radius; });
}

BallStrain ViscoelasticSolver::strain_where(const std::function<bool(const Eigen::Vector3d&)>& inside) const {
  BallStrain b;
  double weighted = 0.0;
  for_each_quadrature_point([&](const Point<3>& x, double jxw, const PointHistory& h) {
    if (!inside(Eigen::Vector3d(x[0], x[1], x[2]))) return;
    const Eigen::Vector3d principal =
        Eigen::SelfAdjointEigenSolver<core::Matrix3>(core::voigt_to_strain(h.state.strain), Eigen::EigenvaluesOnly)
            .eigenvalues();
    const double magnitude = principal.cwiseAbs().maxCoeff();
    weighted += magnitude * jxw;
    b.volume += jxw;
    b.peak = std::max(b.peak, magnitude);
  });
  weighted = Utilities::MPI::sum(weighted, mpi_communicator_);
  b.volume = Utilities::MPI::sum(b.volume, mpi_communicator_);
  b.peak = Utilities::MPI::max(b.peak, mpi_communicator_);
  if (b.volume > 0.0) b.mean = weighted / b.volume;
  return b;
}

double ViscoelasticSolver::boundary_area(unsigned int id) const {
  FEFaceValues<3> fe_face_values(mapping_, fe_, QGaussSimplex<2>(2), update_JxW_values);
  double area = 0.0;
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    for (const auto f : cell->face_indices())
      if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == id) {
        fe_face_values.reinit(cell, f);
        for (unsigned int q = 0; q < fe_face_values.n_quadrature_points; ++q) area += fe_face_values.JxW(q);
      }
  }
  return Utilities::MPI::sum(area, mpi_communicator_);
}

}  // namespace reference_fem
