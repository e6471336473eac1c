#include "meshless/lrpim/lrpim_model.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SparseLU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/step_predictor.hpp"
#include "meshless/efg/gauss_quadrature_tet.hpp"
#include "meshless/mls/cubic_spline_weight.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/support_radii.hpp"
#include "meshless/parallel_for.hpp"
#include "meshless/solvers/kept_factors.hpp"
#include "meshless/solvers/anderson_acceleration.hpp"
#include "meshless/solvers/mumps_lu.hpp"
#include "meshless/solvers/petsc_krylov_solver.hpp"

namespace meshless::lrpim {

namespace {

using Clock = std::chrono::steady_clock;
using Vector6d = Eigen::Matrix<double, 6, 1>;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The 6x3 strain-displacement block of a scalar function with gradient g (engineering Voigt xx yy zz xy yz
// zx).
Eigen::Matrix<double, 6, 3> b_block(const Eigen::Vector3d& g) {
  Eigen::Matrix<double, 6, 3> b = Eigen::Matrix<double, 6, 3>::Zero();
  b(0, 0) = g[0];
  b(1, 1) = g[1];
  b(2, 2) = g[2];
  b(3, 0) = g[1], b(3, 1) = g[0];
  b(4, 1) = g[2], b(4, 2) = g[1];
  b(5, 0) = g[2], b(5, 2) = g[0];
  return b;
}

// d_i per node: the constant node_spacing, or the mean distance to the 6 nearest other nodes.
std::vector<double> node_spacings_of(const LrpimProblem& p, const NodeSearch& search) {
  const int n = static_cast<int>(p.nodes.rows());
  std::vector<double> d(n, p.node_spacing);
  if (!p.local_spacing || n < 7) return d;
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = p.nodes.row(i).transpose();
    const std::vector<int> near = search.nearest(x, 7);
    double sum = 0.0;
    for (size_t k = 1; k < near.size(); ++k) sum += (p.nodes.row(near[k]).transpose() - x).norm();
    d[i] = sum / static_cast<double>(near.size() - 1);
  }
  return d;
}

}  // namespace

// The factorisation of the last tangent: MUMPS (row-major matrix as assembled), Eigen's SparseLU (a
// column-major copy), or a PETSc Krylov method's preconditioner (which references the tangent's arrays: the
// model only rewrites them right before the next factorise), chosen by LrpimProblem::linear_solver.
struct LrpimModel::Solver {
  LrpimLinearSolver kind;
  std::unique_ptr<MumpsLu> mumps;
  std::unique_ptr<PetscKrylovSolver> krylov;
  const core::PointMatrix* nodes = nullptr;
  std::string krylov_options;
  double krylov_tolerance = 1e-9;
  int krylov_iterations = 0;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  bool analysed = false, factored = false;
  std::string name;

  void factorise(const LrpimMatrix& k) {
    if (kind == LrpimLinearSolver::mumps) {
      if (!mumps) mumps = std::make_unique<MumpsLu>(name);
      mumps->factorise(k);
    } else if (kind == LrpimLinearSolver::petsc_krylov) {
      if (!krylov)
        krylov =
            std::make_unique<PetscKrylovSolver>(*nodes, krylov_options, krylov_tolerance, 20000, 0.0, false);
      krylov->set_matrix(k);
    } else {
      Eigen::SparseMatrix<double> c = k;
      c.makeCompressed();
      if (!analysed) lu.analyzePattern(c), analysed = true;
      lu.factorize(c);
      if (lu.info() != Eigen::Success)
        throw std::runtime_error("LrpimModel '" + name +
                                 "': the tangent is singular (SparseLU: " + lu.lastErrorMessage() +
                                 "); check that the body is held (a displacement face or an "
                                 "elastic support)");
    }
    factored = true;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& r) {
    Eigen::VectorXd x;
    if (kind == LrpimLinearSolver::mumps) {
      x = mumps->solve(r);
    } else if (kind == LrpimLinearSolver::petsc_krylov) {
      x = krylov->solve(r);
      krylov_iterations += krylov->last_iterations();
    } else {
      x = lu.solve(r);
    }
    if (!x.allFinite())
      throw std::runtime_error("LrpimModel '" + name + "': the linear solve gave non-finite values");
    return x;
  }
};

// LrpimProblem::balance_rigid_modes. The rigid modes m_j(X) are e_j (j < 3) and e_{j-3} x (X - centre) / length
// (j >= 3), so that all six multipliers are force densities [N/m^3] and all six balances forces [N]. With r(u) the
// local equations' residual, the system is
//   r(u) - body lambda = 0,   support u - s(t) applied = 0
// (body: row 3i + a, column j = int v_i (m_j)_a dV over node i's sub-domain; support: row j, column 3k + a =
// int k_s phi_k (m_j)_a dA over the elastic support; applied: int t-bar . m_j dA), the second being the body's
// balance integrated on the rule of LrpimModel::global_balance. Newton solves it by bordering the factorised tangent
// K: y = K^-1 r, S dlambda = support y - g with S = support K^-1 body (6 x 6), du = -y + K^-1 body dlambda.
struct LrpimModel::RigidBalance {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double length = 1.0;
  Eigen::MatrixXd body;     ///< 3 #nodes by 6 [m^3]
  Eigen::MatrixXd support;  ///< 6 by 3 #nodes [N/m]
  Vector6d applied = Vector6d::Zero();  ///< at load scale 1 [N]
  Vector6d lambda = Vector6d::Zero();   ///< [N/m^3]
  Eigen::MatrixXd solved;   ///< K^-1 body for the current factors
  Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> schur;

  /// 3 by 6: column j is m_j(x).
  Eigen::Matrix<double, 3, 6> modes(const Eigen::Vector3d& x) const {
    Eigen::Matrix<double, 3, 6> m;
    m.leftCols<3>().setIdentity();
    const Eigen::Vector3d d = (x - centre) / length;
    for (int j = 0; j < 3; ++j) m.col(3 + j) = Eigen::Vector3d::Unit(j).cross(d);
    return m;
  }
};

LrpimModel::~LrpimModel() = default;

LrpimModel::LrpimModel(LrpimProblem problem)
    : problem_(std::move(problem)),
      search_(problem_.nodes),
      spacing_(node_spacings_of(problem_, search_)),
      rpim_(problem_.nodes, search_, problem_.node_spacing, problem_.rpim),
      law_(problem_.material) {
  const auto t0 = Clock::now();
  const int n = static_cast<int>(problem_.nodes.rows());
  if (n < problem_.rpim.num_neighbours)
    throw std::invalid_argument("LrpimModel: fewer nodes than RpimParameters::num_neighbours");
  if (!(problem_.alpha_q > 0.0)) throw std::invalid_argument("LrpimModel: alpha_q must be > 0");
  if (problem_.step_times.empty()) throw std::invalid_argument("LrpimModel: no step times");
  if (!problem_.body) throw std::invalid_argument("LrpimModel: LrpimProblem::body is not set");
  const SurfaceBody& body = *problem_.body;
  for (FaceCondition f : problem_.conditions) {
    if (f == FaceCondition::traction && !problem_.traction)
      throw std::invalid_argument("LrpimModel: a traction face needs LrpimProblem::traction");
    if (f == FaceCondition::displacement && !problem_.prescribed_displacement)
      throw std::invalid_argument(
          "LrpimModel: a displacement face needs LrpimProblem::prescribed_displacement");
    if (f == FaceCondition::elastic_support && !problem_.support_stiffness)
      throw std::invalid_argument(
          "LrpimModel: an elastic-support face needs LrpimProblem::support_stiffness");
  }
  if (problem_.local_spacing) rpim_.set_node_spacing(&spacing_);
  const double h = problem_.node_spacing, tol = 1e-9 * h;

  // The test functions other than the plain spline (LrpimTestFunction), from node i's spline w_i at the point
  // (LocalPoint's v, dv): Shepard's w_i / S with S = sum_j w_j over the spheres covering the point,
  // grad (w_i / S) = (grad w_i - (w_i / S) grad S) / S; or the MLS functions of those splines.
  Eigen::VectorXd radii(n);
  for (int j = 0; j < n; ++j) radii[j] = problem_.alpha_q * spacing_[j];
  const double max_radius = radii.maxCoeff();
  const SupportRadii sphere_radii(radii);
  // Built only for the MLS test functions: the others never evaluate it.
  std::optional<MlsShapeFunctions> sphere_mls;
  if (problem_.test_function == LrpimTestFunction::mls)
    sphere_mls.emplace(problem_.nodes, sphere_radii, search_);
  auto retest = [&](int i, LocalPoint* lp, std::vector<NodeHit>* hits) {
    if (problem_.test_function == LrpimTestFunction::mls) {
      const MlsEvaluation e = sphere_mls->evaluate(lp->x, true);
      const auto at = std::lower_bound(e.nodes.begin(), e.nodes.end(), i);
      if (at == e.nodes.end() || *at != i) {  // at the sphere's rim: w_i = 0
        lp->v = 0.0, lp->dv.setZero();
        return;
      }
      const int k = static_cast<int>(at - e.nodes.begin());
      lp->v = e.phi[k], lp->dv = e.dphi.col(k);
      return;
    }
    search_.covering(lp->x, radii, max_radius, hits);
    double sum = 0.0;
    Eigen::Vector3d grad_sum = Eigen::Vector3d::Zero();
    for (const NodeHit& hit : *hits) {
      const double r = std::sqrt(hit.distance_sq), r_j = radii[hit.node];
      const WeightAndSlope ws = cubic_spline_weight_with_slope(r / r_j);
      sum += ws.w;
      if (r > 0.0) grad_sum += ws.dw_ds / (r_j * r) * (lp->x - problem_.nodes.row(hit.node).transpose());
    }
    if (!(sum > 0.0)) {  // the point's own node covers it, so this only happens at its sphere's rim (v = 0)
      lp->v = 0.0, lp->dv.setZero();
      return;
    }
    lp->v /= sum;
    lp->dv = (lp->dv - lp->v * grad_sum) / sum;
  };
  const bool retested = problem_.test_function != LrpimTestFunction::spline;

  // Local sub-domains and boundaries of the nodes that carry equations (constrained nodes have u_i = u-bar).
  std::vector<std::vector<LocalIntegrationPoint>> vol(n), rea(n), sup(n), tra(n);
  constrained_.assign(n, 0);
  // Per node, reduced after the loop: the smallest reciprocal condition number of its moment matrices and the
  // divergence defect of its sub-domain's quadrature.
  std::vector<double> node_rcond(n, 1.0), node_defect(n, 0.0);
  parallel_for(n, 4, [&](int i) {
    const Eigen::Vector3d c = problem_.nodes.row(i).transpose();
    const double r_q = problem_.alpha_q * spacing_[i];
    const LocalSurface local(body, c, r_q, tol);
    bool held = false;
    for (int t : local.touching()) held = held || condition(body.label(t)) == FaceCondition::displacement;
    constrained_[i] = held ? 1 : 0;
    if (held) return;
    RpimEvaluation e;
    std::vector<NodeHit> hits;
    auto tabulate = [&](const LocalPoint& lp, const Eigen::Vector3d& normal, bool gradients) {
      LocalIntegrationPoint p;
      p.test_node = i;
      p.weight = lp.weight;
      p.v = lp.v;
      p.dv = lp.dv;
      p.normal = normal;
      p.x = lp.x;
      rpim_.evaluate(lp.x, gradients, &e);
      node_rcond[i] = std::min(node_rcond[i], e.rcond);
      p.support = e.nodes;
      if (gradients)
        p.dphi = e.dphi;
      else
        p.phi = e.phi;
      return p;
    };
    for (LocalPoint& lp : sphere_points(c, r_q, local, problem_.rule)) {
      if (retested) retest(i, &lp, &hits);
      if (lp.weight > 0.0 && lp.dv.squaredNorm() > 0.0)
        vol[i].push_back(tabulate(lp, Eigen::Vector3d::Zero(), true));
    }
    // The boundary: every triangle within r_q. Its points feed the divergence identity (free faces too: v n
    // is there as well) and, by the triangle's condition, the reaction, support or traction integrals.
    Eigen::Vector3d boundary = Eigen::Vector3d::Zero();
    for (int t : local.triangles()) {
      const FaceCondition f = condition(body.label(t));
      const Eigen::Vector3d normal = body.normal(t);
      for (LocalPoint& lp :
           triangle_points(c, r_q, body.corner(t, 0), body.corner(t, 1), body.corner(t, 2), problem_.rule)) {
        if (retested) retest(i, &lp, &hits);
        boundary += lp.weight * lp.v * normal;
        if (f == FaceCondition::traction) {
          LocalIntegrationPoint p;
          p.test_node = i;
          p.weight = lp.weight;
          p.v = lp.v;
          p.dv.setZero();
          p.normal = normal;
          p.x = lp.x;
          tra[i].push_back(std::move(p));
        } else if (f == FaceCondition::displacement) {
          rea[i].push_back(tabulate(lp, normal, true));
        } else if (f == FaceCondition::elastic_support) {
          const double k_s = problem_.support_stiffness(lp.x);
          if (!(k_s > 0.0)) continue;
          LocalIntegrationPoint p = tabulate(lp, normal, false);
          p.stiffness = k_s;
          sup[i].push_back(std::move(p));
        }
      }
    }
    Eigen::Vector3d volume = Eigen::Vector3d::Zero();
    double measure = 0.0;
    for (const LocalIntegrationPoint& p : vol[i]) volume += p.weight * p.dv, measure += p.weight;
    if (measure > 0.0) {
      const Eigen::Vector3d xi = (boundary - volume) / measure;
      node_defect[i] = xi.norm() * r_q;
      if (problem_.divergence_correction)
        for (LocalIntegrationPoint& p : vol[i]) p.dv += xi;
    }
  });
  const double min_rcond = std::accumulate(node_rcond.begin(), node_rcond.end(), 1.0,
                                           [](double a, double b) { return std::min(a, b); });
  const double defect = std::accumulate(node_defect.begin(), node_defect.end(), 0.0,
                                        [](double a, double b) { return std::max(a, b); });
  // A free node whose sub-domain has no point inside the body would carry an empty row: name it here rather
  // than let the factorisation report a "zero column" of a permuted matrix.
  for (int i = 0; i < n; ++i)
    if (!constrained_[i] && vol[i].empty()) {
      std::ostringstream m;
      m << "LrpimModel '" << problem_.name << "': node " << i << " at (" << 1e3 * problem_.nodes(i, 0) << ", "
        << 1e3 * problem_.nodes(i, 1) << ", " << 1e3 * problem_.nodes(i, 2)
        << ") mm has no point of its local sub-domain (radius " << 1e3 * problem_.alpha_q * spacing_[i]
        << " mm) inside the body, so it carries no equations; the node lies outside the surface or the "
           "surface is "
           "not closed there. Remove the node or mend the surface";
      throw std::runtime_error(m.str());
    }
  auto gather = [n](std::vector<std::vector<LocalIntegrationPoint>>& per_node,
                    std::vector<LocalIntegrationPoint>* all, std::vector<int>* begin) {
    begin->assign(n + 1, 0);
    size_t total = 0;
    for (int i = 0; i < n; ++i) total += per_node[i].size();
    all->reserve(total);
    for (int i = 0; i < n; ++i) {
      (*begin)[i] = static_cast<int>(all->size());
      std::move(per_node[i].begin(), per_node[i].end(), std::back_inserter(*all));
      std::vector<LocalIntegrationPoint>().swap(per_node[i]);
    }
    (*begin)[n] = static_cast<int>(all->size());
  };
  gather(vol, &volume_, &volume_begin_);
  gather(rea, &reaction_, &reaction_begin_);
  gather(sup, &support_, &support_begin_);
  gather(tra, &traction_, &traction_begin_);
  states_.assign(volume_.size() + reaction_.size(), core::KelvinState{});
  u_ = Eigen::VectorXd::Zero(3 * n);
  // Constrained rows read s (u_i - u-bar_i): s = K1 h [N/m] gives them the size of a stiffness row.
  constraint_scale_ = problem_.material.K1 * h;
  build_pattern();
  statistics_.num_nodes = n;
  for (std::uint8_t b : constrained_) statistics_.num_constrained_nodes += b;
  statistics_.num_volume_points = static_cast<int>(volume_.size());
  statistics_.num_reaction_points = static_cast<int>(reaction_.size());
  statistics_.num_support_points = static_cast<int>(support_.size());
  statistics_.num_traction_points = static_cast<int>(traction_.size());
  statistics_.min_rcond = min_rcond;
  statistics_.divergence_defect = defect;
  statistics_.matrix_entries = tangent_.nonZeros();
  solver_ = std::make_unique<Solver>();
  solver_->kind = problem_.linear_solver;
  solver_->name = problem_.name;
  solver_->nodes = &problem_.nodes;
  solver_->krylov_options = problem_.krylov_options;
  solver_->krylov_tolerance = problem_.krylov_tolerance;
  set_up_rigid_balance();
  statistics_.setup_seconds = seconds_since(t0);
}

void LrpimModel::set_up_rigid_balance() {
  if (!problem_.balance_rigid_modes) return;
  const SurfaceBody& body = *problem_.body;
  bool supported = false;
  for (int t = 0; t < body.num_triangles(); ++t) {
    const FaceCondition f = condition(body.label(t));
    if (f == FaceCondition::displacement) return;  // the constraint holds the rigid modes
    supported = supported || f == FaceCondition::elastic_support;
  }
  if (!supported) return;
  const int n = statistics_.num_nodes;
  auto b = std::make_unique<RigidBalance>();
  b->centre = problem_.nodes.colwise().mean().transpose();
  b->length = std::max((problem_.nodes.rowwise() - b->centre.transpose()).rowwise().norm().maxCoeff(),
                       problem_.node_spacing);
  b->body = Eigen::MatrixXd::Zero(3 * n, 6);
  parallel_for(n, 64, [&](int i) {
    for (int q = volume_begin_[i]; q < volume_begin_[i + 1]; ++q)
      b->body.middleRows<3>(3 * i) += volume_[q].weight * volume_[q].v * b->modes(volume_[q].x);
  });
  // The support and the load on global_balance()'s rule, so that its report of the balance reads what was imposed.
  b->support = Eigen::MatrixXd::Zero(6, 3 * n);
  RpimEvaluation e;
  for_each_balance_point([&](FaceCondition f, const Eigen::Vector3d& x, double w) {
    if (f == FaceCondition::traction) return;  // integrate_balance_load()
    const Eigen::Matrix<double, 6, 3> mt = b->modes(x).transpose();
    rpim_.evaluate(x, false, &e);
    const double k_s = problem_.support_stiffness(x);
    for (int k = 0; k < e.size(); ++k) b->support.middleCols<3>(3 * e.nodes[k]) += w * k_s * e.phi[k] * mt;
  });
  balance_ = std::move(b);
  integrate_balance_load();
}

void LrpimModel::integrate_balance_load() {
  if (!balance_) return;
  balance_->applied.setZero();
  for_each_balance_point([&](FaceCondition f, const Eigen::Vector3d& x, double w) {
    if (f == FaceCondition::traction) balance_->applied += w * balance_->modes(x).transpose() * problem_.traction(x);
  });
}

void LrpimModel::restart(LrpimLoad load) {
  if (!load.traction && !traction_.empty())
    throw std::invalid_argument("LrpimModel::restart: the body has traction faces, so the load needs a traction");
  if (!std::is_sorted(load.step_times.begin(), load.step_times.end()))
    throw std::invalid_argument("LrpimModel::restart: step times must not decrease");
  problem_.traction = std::move(load.traction);
  problem_.load_scale = std::move(load.load_scale);
  problem_.step_times = std::move(load.step_times);
  std::fill(states_.begin(), states_.end(), core::KelvinState{});
  u_.setZero();
  time_ = 0.0;
  steps_.clear();
  statistics_.assembly_seconds = statistics_.solve_seconds = 0.0;
  statistics_.factorisations = 0;
  statistics_.krylov_iterations = 0;
  solver_->krylov_iterations = 0;
  solver_->factored = false;  // the next step factorises its own tangent, as a new model's first step does
  if (balance_) {
    balance_->lambda.setZero();
    integrate_balance_load();
  }
}

void LrpimModel::for_each_balance_point(
    const std::function<void(FaceCondition, const Eigen::Vector3d&, double)>& at) const {
  // Independent of the test functions' spheres (LrpimGlobalBalance). The reaction -k_s u_h is not a
  // polynomial: on the CI lung a degree-2 rule read the imbalance as 1.50 % (force) and 3.30 % (moment), the
  // edge midpoints as 0.97 % and 2.5 %; degrees 4 and 6 agree to 0.05 % (1.27 / 1.30 % and 2.98 / 3.02 %).
  const SurfaceBody& body = *problem_.body;
  const SimplexRule rule = triangle_rule(6);
  for (int t = 0; t < body.num_triangles(); ++t) {
    const FaceCondition f = condition(body.label(t));
    if (f != FaceCondition::traction && f != FaceCondition::elastic_support) continue;
    const Eigen::Vector3d a = body.corner(t, 0), e1 = body.corner(t, 1) - a, e2 = body.corner(t, 2) - a;
    for (int q = 0; q < rule.size(); ++q)  // the reference triangle's area is 1/2
      at(f, a + rule.points[q].x() * e1 + rule.points[q].y() * e2, 2.0 * body.area(t) * rule.weights[q]);
  }
}

LrpimBalanceCorrection LrpimModel::balance_correction() const {
  LrpimBalanceCorrection c;
  if (!balance_) return c;
  c.active = true;
  for (const LocalIntegrationPoint& p : volume_) {
    const Eigen::Vector3d f = p.weight * p.v * (balance_->modes(p.x) * balance_->lambda);
    c.net_force += f, c.net_moment += p.x.cross(f);
  }
  return c;
}

void LrpimModel::build_pattern() {
  const int n = static_cast<int>(problem_.nodes.rows());
  std::vector<std::vector<int>> cols(n);
#pragma omp parallel for schedule(dynamic, 16)
  for (int i = 0; i < n; ++i) {
    std::vector<int>& c = cols[i];
    c.push_back(i);
    for (int q = volume_begin_[i]; q < volume_begin_[i + 1]; ++q)
      c.insert(c.end(), volume_[q].support.begin(), volume_[q].support.end());
    for (int q = reaction_begin_[i]; q < reaction_begin_[i + 1]; ++q)
      c.insert(c.end(), reaction_[q].support.begin(), reaction_[q].support.end());
    for (int q = support_begin_[i]; q < support_begin_[i + 1]; ++q)
      c.insert(c.end(), support_[q].support.begin(), support_[q].support.end());
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }
  row_begin_.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) row_begin_[i + 1] = row_begin_[i] + static_cast<long long>(cols[i].size());
  columns_.resize(row_begin_[n]);
  for (int i = 0; i < n; ++i) std::copy(cols[i].begin(), cols[i].end(), columns_.begin() + row_begin_[i]);
  const long long nnz = 9 * row_begin_[n];
  if (nnz > std::numeric_limits<int>::max())
    throw std::runtime_error(
        "LrpimModel: the tangent has more entries than a 32-bit index holds; use fewer nodes");
  tangent_.resize(3 * n, 3 * n);
  tangent_.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = tangent_.outerIndexPtr();
  int* inner = tangent_.innerIndexPtr();
  for (int i = 0; i < n; ++i) {
    const long long len = row_begin_[i + 1] - row_begin_[i];
    for (int a = 0; a < 3; ++a) {
      const long long start = 9 * row_begin_[i] + 3 * a * len;
      outer[3 * i + a] = static_cast<int>(start);
      for (long long k = 0; k < len; ++k)
        for (int b = 0; b < 3; ++b) inner[start + 3 * k + b] = 3 * columns_[row_begin_[i] + k] + b;
    }
  }
  outer[3 * n] = static_cast<int>(nnz);
  std::fill(tangent_.valuePtr(), tangent_.valuePtr() + nnz, 0.0);
}

// Residual of node i, component j (MLPG1 with test function v_i e_j over Omega_s, boundary Gamma_s):
//   R_ij = int_{Omega_s} (B(grad v_i) e_j) . sigma(u) dV - int_{Gamma_su} v_i (sigma(u) n)_j dA
//          + int_{Gamma_sk} v_i k_s u_j dA - s(t) int_{Gamma_st} v_i t-bar_j dA
// (the sphere's interior surface carries no term: v_i = 0 there; Gamma_sk is the elastic support, t = -k_s
// u). Tangent: sigma -> C_k (consistent tangent) and k_s u -> k_s phi.
void LrpimModel::assemble(double time, double dt, LrpimMatrix* k, Eigen::VectorXd* r,
                          std::vector<core::KelvinState>* new_states) const {
  const int n = static_cast<int>(problem_.nodes.rows());
  r->setZero(3 * n);
  new_states->resize(states_.size());
  double* values = k ? k->valuePtr() : nullptr;
  const double s = problem_.load_scale ? problem_.load_scale(time) : 1.0;
  parallel_for(n, 16, [&](int i) {
    const long long row = row_begin_[i], len = row_begin_[i + 1] - row_begin_[i];
    const int* cols = columns_.data() + row;
    // The slot of each column node in row i, by a per-thread table (set for this row, cleared after it).
    thread_local std::vector<int> position;
    if (values) {
      if (static_cast<int>(position.size()) != n) position.assign(n, -1);
      for (long long k = 0; k < len; ++k) position[cols[k]] = static_cast<int>(k);
    }
    // The three rows of block (i, node) start here; row a is 3 len entries after row a - 1.
    auto block = [&](int node) { return values + 9 * row + 3 * position[node]; };
    if (values) std::fill(values + 9 * row, values + 9 * (row + len), 0.0);
    Eigen::Ref<Eigen::Vector3d> ri = r->segment<3>(3 * i);
    if (constrained_[i]) {
      const Eigen::Vector3d ubar = problem_.prescribed_displacement(problem_.nodes.row(i).transpose());
      ri = constraint_scale_ * (u_.segment<3>(3 * i) - ubar);
      if (values) {
        double* v = block(i);
        for (int a = 0; a < 3; ++a) v[3 * a * len + a] += constraint_scale_;
        for (long long k = 0; k < len; ++k) position[cols[k]] = -1;
      }
      return;
    }
    auto add_point = [&](const LocalIntegrationPoint& p, size_t state, bool reaction) {
      // eps = sum_a B(grad phi_a) u_a with B's zero pattern spelt out (the EFG's update_material).
      core::Vector6 eps = core::Vector6::Zero();
      for (int a = 0; a < static_cast<int>(p.support.size()); ++a) {
        const double gx = p.dphi(0, a), gy = p.dphi(1, a), gz = p.dphi(2, a);
        const Eigen::Vector3d u = u_.segment<3>(3 * p.support[a]);
        eps[0] += gx * u.x();
        eps[1] += gy * u.y();
        eps[2] += gz * u.z();
        eps[3] += gy * u.x() + gx * u.y();
        eps[4] += gz * u.y() + gy * u.z();
        eps[5] += gz * u.x() + gx * u.z();
      }
      // Test operator (3x6): B(grad v)^T for the volume, -v B(n)^T for the reaction sigma n.
      const Eigen::Matrix<double, 3, 6> test =
          reaction ? Eigen::Matrix<double, 3, 6>(-p.v * b_block(p.normal).transpose())
                   : Eigen::Matrix<double, 3, 6>(b_block(p.dv).transpose());
      if (!values) {  // a residual-only iteration: the law's stress without its tangent
        ri += p.weight * test * law_.updated_stress(states_[state], eps, dt, &(*new_states)[state]);
        return;
      }
      const core::KelvinResponse resp = law_.update(states_[state], eps, dt, &(*new_states)[state]);
      ri += p.weight * test * resp.stress;
      const Eigen::Matrix<double, 3, 6> tc = p.weight * test * resp.tangent;
      for (int a = 0; a < static_cast<int>(p.support.size()); ++a) {
        const double hx = p.dphi(0, a), hy = p.dphi(1, a), hz = p.dphi(2, a);
        double* v = block(p.support[a]);
        // (test C_k) B(grad phi_a) with B's zero pattern spelt out: 27 multiplications.
        for (int c = 0; c < 3; ++c, v += 3 * len) {
          v[0] += tc(c, 0) * hx + tc(c, 3) * hy + tc(c, 5) * hz;
          v[1] += tc(c, 1) * hy + tc(c, 3) * hx + tc(c, 4) * hz;
          v[2] += tc(c, 2) * hz + tc(c, 4) * hy + tc(c, 5) * hx;
        }
      }
    };
    for (int q = volume_begin_[i]; q < volume_begin_[i + 1]; ++q) add_point(volume_[q], q, false);
    for (int q = reaction_begin_[i]; q < reaction_begin_[i + 1]; ++q)
      add_point(reaction_[q], volume_.size() + q, true);
    for (int q = support_begin_[i]; q < support_begin_[i + 1]; ++q) {
      const LocalIntegrationPoint& p = support_[q];
      const double c = p.weight * p.v * p.stiffness;
      for (int a = 0; a < static_cast<int>(p.support.size()); ++a) {
        ri += c * p.phi[a] * u_.segment<3>(3 * p.support[a]);
        if (!values) continue;
        double* v = block(p.support[a]);
        for (int b = 0; b < 3; ++b) v[3 * b * len + b] += c * p.phi[a];
      }
    }
    for (int q = traction_begin_[i]; q < traction_begin_[i + 1]; ++q) {
      const LocalIntegrationPoint& p = traction_[q];
      ri -= s * p.weight * p.v * problem_.traction(p.x);
    }
    if (values)
      for (long long k = 0; k < len; ++k) position[cols[k]] = -1;
  });
  // A non-finite value would only surface as a failed solve; name the node instead.
  for (int i = 0; i < n; ++i) {
    bool finite = r->segment<3>(3 * i).allFinite();
    if (values)
      finite = finite && Eigen::Map<const Eigen::VectorXd>(values + 9 * row_begin_[i],
                                                           9 * (row_begin_[i + 1] - row_begin_[i]))
                             .allFinite();
    if (!finite) {
      std::ostringstream m;
      m << "LrpimModel '" << problem_.name << "': non-finite residual or tangent in the rows of node " << i
        << " at (" << 1e3 * problem_.nodes.row(i) << ") mm (" << volume_begin_[i + 1] - volume_begin_[i]
        << " volume, " << support_begin_[i + 1] - support_begin_[i] << " support, "
        << traction_begin_[i + 1] - traction_begin_[i] << " traction points)";
      throw std::runtime_error(m.str());
    }
  }
}

void LrpimModel::run(const std::function<void(const LrpimModel&, const LrpimStepRecord&)>& on_step) {
  const int n = statistics_.num_nodes;
  // The external load's size at full load, for the relative stopping test.
  double f_ext = 0.0;
  {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * n);
    for (const LocalIntegrationPoint& p : traction_)
      f.segment<3>(3 * p.test_node) += p.weight * p.v * problem_.traction(p.x);
    f_ext = f.norm();
  }
  Eigen::VectorXd r;
  std::vector<core::KelvinState> trial;
  const bool full_newton = !(problem_.refactor_contraction > 0.0);
  // The unknowns of the fixed-point iteration on kept factors, u and (when imposed) the balance multipliers, as one
  // vector for the predictor and the Anderson mixing (the EFG's, docs/MESHLESS.md §2).
  const int n_lambda = balance_ ? 6 : 0;
  auto unknowns = [&] {
    Eigen::VectorXd z(3 * n + n_lambda);
    z.head(3 * n) = u_;
    if (balance_) z.tail(6) = balance_->lambda;
    return z;
  };
  auto set_unknowns = [&](const Eigen::VectorXd& z) {
    u_ = z.head(3 * n);
    if (balance_) balance_->lambda = z.tail(6);
  };
  AndersonAcceleration mixing(full_newton ? 0 : problem_.anderson_depth);
  std::optional<Eigen::VectorXd> previous_start;  // the unknowns at the start of the last step, at time previous_t
  double previous_t = 0.0;
  for (double t_new : problem_.step_times) {
    const auto t_step = Clock::now();
    const double dt = t_new - time_;
    if (dt < 0.0) throw std::invalid_argument("LrpimModel: step times must not decrease");
    const Eigen::VectorXd z_start = unknowns();
    // Extrapolated start while the load keeps its rate (EfgOptions::extrapolate_start explains the rule).
    if (problem_.extrapolate_start && previous_start &&
        core::load_keeps_its_rate(problem_.load_scale, previous_t, time_, t_new))
      set_unknowns(z_start + (dt / (time_ - previous_t)) * (z_start - *previous_start));
    mixing.start_sequence();
    for (int i = 0; i < n; ++i)
      if (constrained_[i])
        u_.segment<3>(3 * i) = problem_.prescribed_displacement(problem_.nodes.row(i).transpose());
    LrpimStepRecord rec;
    rec.time = t_new;
    double reference = f_ext, last = 0.0;
    const double load = problem_.load_scale ? problem_.load_scale(t_new) : 1.0;
    Vector6d g = Vector6d::Zero();  // the balance equations' residual (RigidBalance)
    // The residual of the local equations (and of the balance, when it is imposed) at u_, lambda.
    auto residual = [&](LrpimMatrix* k) {
      assemble(t_new, dt, k, &r, &trial);
      if (!balance_) return r.norm();
      r -= balance_->body * balance_->lambda;
      g = balance_->support * u_ - load * balance_->applied;
      return std::sqrt(r.squaredNorm() + g.squaredNorm());
    };
    Eigen::VectorXd z_before, plain_update;  // the last solve's unknowns and its unmixed update
    bool last_mixed = false;
    // This step's run of updates on the current factors: ||R|| where it began and how many updates it has made.
    double run_start = 0.0;
    int run_length = 0;
    for (int it = 0;; ++it) {
      auto ta = Clock::now();
      const double rn = residual(full_newton ? &tangent_ : nullptr);
      if (last_mixed && !(rn <= last)) {
        // The mix raised ||R||: take the plain update from the same iterate (the EFG's guard, docs/MESHLESS.md §2).
        set_unknowns(z_before + plain_update);
        mixing.reset();
        last_mixed = false;
        ++rec.rejected_mixes;
        rec.assembly_seconds += seconds_since(ta);
        continue;
      }
      if (it == 0) reference = std::max(reference, rn);
      rec.residual = reference > 0.0 ? rn / reference : rn;
      rec.residuals.push_back(rec.residual);
      const bool converged = rn <= problem_.newton_tolerance * reference || reference == 0.0;
      // Modified Newton: keep the factors while they contract the residual enough.
      if (it == 0) run_start = rn, run_length = 0;
      const bool refactor = !converged && (full_newton || !solver_->factored ||
                                           kept_factors_too_slow(rn, last, run_start, run_length,
                                                                 problem_.newton_tolerance * reference, it,
                                                                 problem_.refactor_contraction,
                                                                 problem_.max_newton_iterations));
      if (refactor && !full_newton) residual(&tangent_);
      rec.assembly_seconds += seconds_since(ta);
      if (converged) break;
      if (it == problem_.max_newton_iterations) {
        std::ostringstream s;
        // The set-up's diagnostics say whether a smaller step can help at all: on the real right lobe (docs/LRPIM.md
        // §6) Newton failed at any step size, with the worst support at rcond 1e-12 and a defect of 0.13.
        s << "LrpimModel '" << problem_.name << "': Newton did not converge at t = " << t_new
          << " s (relative residual " << rec.residual << " after " << it << " iterations). The set-up's worst RPIM "
          << "support has rcond " << statistics_.min_rcond << " and the local sub-domains' divergence defect is "
          << statistics_.divergence_defect << " (the CI lung: 6.9e-10 and 0.039). When these are near the CI lung's, "
          << "shorten the steps or lower the load; when they are far off, the local equations do not balance the "
          << "body and no step size helps: refine the node cloud or smooth the surface where the supports are poor "
          << "(docs/LRPIM.md §6)";
        throw std::runtime_error(s.str());
      }
      last = rn;
      auto ts = Clock::now();
      if (refactor) {
        solver_->factorise(tangent_);
        ++rec.factorisations;
        if (balance_) {
          balance_->solved.resize(3 * n, 6);
          for (int j = 0; j < 6; ++j) balance_->solved.col(j) = solver_->solve(balance_->body.col(j));
          balance_->schur.compute(balance_->support * balance_->solved);
          if (!balance_->schur.isInvertible())
            throw std::runtime_error("LrpimModel '" + problem_.name +
                                     "': the six balance equations are singular on this tangent: the elastic "
                                     "support does not hold every rigid motion (a support region on one line?); "
                                     "enlarge the fixed region, or set LrpimProblem::balance_rigid_modes = false");
        }
      }
      if (refactor) run_start = rn, run_length = 0;
      ++run_length;
      z_before = unknowns();
      const Eigen::VectorXd y = solver_->solve(r);
      u_ -= y;
      if (balance_) {
        const Vector6d dlambda = balance_->schur.solve(balance_->support * y - g);
        u_ += balance_->solved * dlambda;
        balance_->lambda += dlambda;
      }
      // Mix only updates on one set of factors; a fresh factorisation restarts the mix.
      last_mixed = false;
      if (refactor || full_newton) {
        mixing.reset();
      } else if (mixing.depth() > 0) {
        plain_update = unknowns() - z_before;
        set_unknowns(z_before + mixing.next_update(z_before, plain_update));
        last_mixed = mixing.history() > 0;
      }
      rec.solve_seconds += seconds_since(ts);
      rec.newton_iterations = it + 1;
    }
    states_ = trial;
    previous_start = z_start;
    previous_t = time_;
    time_ = t_new;
    rec.wall_seconds = seconds_since(t_step);
    statistics_.assembly_seconds += rec.assembly_seconds;
    statistics_.solve_seconds += rec.solve_seconds;
    statistics_.factorisations += rec.factorisations;
    statistics_.krylov_iterations = solver_->krylov_iterations;
    steps_.push_back(rec);
    if (on_step) on_step(*this, rec);
  }
}

void LrpimModel::linear_system(double time, double dt, LrpimMatrix* k, Eigen::VectorXd* r) const {
  *k = tangent_;
  std::vector<core::KelvinState> trial;
  assemble(time, dt, k, r, &trial);
}

LrpimGlobalBalance LrpimModel::global_balance() const {
  LrpimGlobalBalance b;
  const double s = problem_.load_scale ? problem_.load_scale(time_) : 1.0;
  for_each_balance_point([&](FaceCondition f, const Eigen::Vector3d& x, double w) {
    if (f == FaceCondition::traction) {
      const Eigen::Vector3d force = w * s * problem_.traction(x);
      b.applied_force += force, b.applied_moment += x.cross(force);
    } else {
      const Eigen::Vector3d force = -w * problem_.support_stiffness(x) * displacement_at(x);
      b.support_force += force, b.support_moment += x.cross(force);
    }
  });
  for (const LocalIntegrationPoint& p : traction_)
    b.test_weighted_applied += p.weight * p.v * s * problem_.traction(p.x);
  for (const LocalIntegrationPoint& p : support_) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (int a = 0; a < static_cast<int>(p.support.size()); ++a)
      u += p.phi[a] * u_.segment<3>(3 * p.support[a]);
    b.test_weighted_support -= p.weight * p.v * p.stiffness * u;
  }
  return b;
}

Eigen::Vector3d LrpimModel::displacement_at(const Eigen::Vector3d& x) const {
  const RpimEvaluation e = rpim_.evaluate(x, false);
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (int a = 0; a < e.size(); ++a) u += e.phi[a] * u_.segment<3>(3 * e.nodes[a]);
  return u;
}

core::Vector6 LrpimModel::strain_at(const Eigen::Vector3d& x) const {
  const RpimEvaluation e = rpim_.evaluate(x, true);
  core::Vector6 eps = core::Vector6::Zero();
  for (int a = 0; a < e.size(); ++a) eps += b_block(e.dphi.col(a)) * u_.segment<3>(3 * e.nodes[a]);
  return eps;
}

}  // namespace meshless::lrpim
