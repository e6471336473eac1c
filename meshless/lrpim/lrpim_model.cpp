#include "meshless/lrpim/lrpim_model.hpp"

#include <Eigen/SparseLU>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace meshless::lrpim {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The 6x3 strain-displacement block of a scalar function with gradient g (engineering Voigt xx yy zz xy yz zx).
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

}  // namespace

LrpimModel::LrpimModel(LrpimProblem problem)
    : problem_(std::move(problem)),
      search_(problem_.nodes),
      rpim_(problem_.nodes, search_, problem_.node_spacing, problem_.rpim),
      law_(problem_.material) {
  const auto t0 = Clock::now();
  const int n = static_cast<int>(problem_.nodes.rows());
  if (n < problem_.rpim.num_neighbours)
    throw std::invalid_argument("LrpimModel: fewer nodes than RpimParameters::num_neighbours");
  if (!(problem_.alpha_q > 0.0)) throw std::invalid_argument("LrpimModel: alpha_q must be > 0");
  if (problem_.step_times.empty()) throw std::invalid_argument("LrpimModel: no step times");
  bool has_displacement = false;
  for (int f = 0; f < kBoxFaces; ++f) {
    if (problem_.faces[f] == FaceCondition::displacement) has_displacement = true;
    if (problem_.faces[f] == FaceCondition::traction && !problem_.traction)
      throw std::invalid_argument("LrpimModel: a traction face needs LrpimProblem::traction");
  }
  if (has_displacement && !problem_.prescribed_displacement)
    throw std::invalid_argument("LrpimModel: a displacement face needs LrpimProblem::prescribed_displacement");
  const double h = problem_.node_spacing, r_q = problem_.alpha_q * h, tol = 1e-9 * h;
  constrained_.assign(n, false);
  for (int i = 0; i < n; ++i)
    for (int f = 0; f < kBoxFaces; ++f)
      if (problem_.faces[f] == FaceCondition::displacement &&
          problem_.body.on_face(f, problem_.nodes.row(i).transpose(), tol))
        constrained_[i] = true;

  // Local sub-domains and boundaries of the nodes that carry equations (constrained nodes have u_i = u-bar).
  std::vector<std::vector<LocalIntegrationPoint>> vol(n), rea(n), tra(n);
  double min_rcond = 1.0, defect = 0.0;
  std::string error;
#pragma omp parallel for schedule(dynamic, 4) reduction(min : min_rcond) reduction(max : defect)
  for (int i = 0; i < n; ++i) {
    if (constrained_[i]) continue;
    try {
      const Eigen::Vector3d c = problem_.nodes.row(i).transpose();
      RpimEvaluation e;
      auto tabulate = [&](const LocalPoint& lp, const Eigen::Vector3d& normal, bool with_trial) {
        LocalIntegrationPoint p;
        p.test_node = i;
        p.weight = lp.weight;
        p.v = lp.v;
        p.dv = lp.dv;
        p.normal = normal;
        p.x = lp.x;
        if (with_trial) {
          rpim_.evaluate(lp.x, true, &e);
          min_rcond = std::min(min_rcond, e.rcond);
          p.support = e.nodes;
          p.dphi = e.dphi;
        }
        return p;
      };
      for (const LocalPoint& lp : sphere_points(c, r_q, problem_.body, problem_.rule))
        if (lp.weight > 0.0 && lp.dv.squaredNorm() > 0.0) vol[i].push_back(tabulate(lp, Eigen::Vector3d::Zero(), true));
      for (int f = 0; f < kBoxFaces; ++f) {
        if (problem_.faces[f] == FaceCondition::free_surface) continue;
        const bool reaction = problem_.faces[f] == FaceCondition::displacement;
        for (const LocalPoint& lp : face_points(c, r_q, problem_.body, f, problem_.rule)) {
          if (!(lp.weight > 0.0 && lp.v > 0.0)) continue;
          (reaction ? rea[i] : tra[i]).push_back(tabulate(lp, problem_.body.normal(f), reaction));
        }
      }
      // The divergence defect of this local domain, over every face (free ones included: v n is there too).
      Eigen::Vector3d boundary = Eigen::Vector3d::Zero(), volume = Eigen::Vector3d::Zero();
      double measure = 0.0;
      for (int f = 0; f < kBoxFaces; ++f)
        for (const LocalPoint& lp : face_points(c, r_q, problem_.body, f, problem_.rule))
          boundary += lp.weight * lp.v * problem_.body.normal(f);
      for (const LocalIntegrationPoint& p : vol[i]) volume += p.weight * p.dv, measure += p.weight;
      if (measure > 0.0) {
        const Eigen::Vector3d xi = (boundary - volume) / measure;
        defect = std::max(defect, xi.norm() * r_q);
        if (problem_.divergence_correction)
          for (LocalIntegrationPoint& p : vol[i]) p.dv += xi;
      }
    } catch (const std::exception& ex) {
#pragma omp critical
      if (error.empty()) error = ex.what();
    }
  }
  if (!error.empty()) throw std::runtime_error("LrpimModel set-up: " + error);
  for (int i = 0; i < n; ++i) {
    volume_.insert(volume_.end(), vol[i].begin(), vol[i].end());
    reaction_.insert(reaction_.end(), rea[i].begin(), rea[i].end());
    traction_.insert(traction_.end(), tra[i].begin(), tra[i].end());
  }
  states_.assign(volume_.size() + reaction_.size(), core::KelvinState{});
  u_ = Eigen::VectorXd::Zero(3 * n);
  // Constrained rows read s (u_i - u-bar_i): s = K1 h [N/m] gives them the size of a stiffness row.
  constraint_scale_ = problem_.material.K1 * h;
  statistics_.num_nodes = n;
  for (bool b : constrained_) statistics_.num_constrained_nodes += b;
  statistics_.num_volume_points = static_cast<int>(volume_.size());
  statistics_.num_reaction_points = static_cast<int>(reaction_.size());
  statistics_.num_traction_points = static_cast<int>(traction_.size());
  statistics_.min_rcond = min_rcond;
  statistics_.divergence_defect = defect;
  statistics_.setup_seconds = seconds_since(t0);
}

// Residual of node i, component j (MLPG1 with test function v_i e_j over Omega_s, boundary Gamma_s):
//   R_ij = int_{Omega_s} (B(grad v_i) e_j) . sigma(u) dV - int_{Gamma_su} v_i (sigma(u) n)_j dA
//          - s(t) int_{Gamma_st} v_i t-bar_j dA
// (the sphere's interior surface carries no term: v_i = 0 there). Tangent: sigma -> C_k (consistent tangent).
void LrpimModel::assemble(double time, double dt, Eigen::SparseMatrix<double>* k, Eigen::VectorXd* r,
                          std::vector<core::KelvinState>* new_states) {
  const int n = statistics_.num_nodes;
  r->setZero(3 * n);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(volume_.size() * 60 + reaction_.size() * 60 + 3 * n);
  new_states->resize(states_.size());
  auto add_point = [&](const LocalIntegrationPoint& p, size_t state, bool reaction) {
    core::Vector6 eps = core::Vector6::Zero();
    for (int a = 0; a < static_cast<int>(p.support.size()); ++a)
      eps += b_block(p.dphi.col(a)) * u_.segment<3>(3 * p.support[a]);
    const core::KelvinResponse resp = law_.update(states_[state], eps, dt, &(*new_states)[state]);
    // Test operator (3x6): B(grad v)^T for the volume, -v B(n)^T for the reaction sigma n.
    const Eigen::Matrix<double, 3, 6> test =
        reaction ? Eigen::Matrix<double, 3, 6>(-p.v * b_block(p.normal).transpose())
                 : Eigen::Matrix<double, 3, 6>(b_block(p.dv).transpose());
    r->segment<3>(3 * p.test_node) += p.weight * test * resp.stress;
    const Eigen::Matrix<double, 3, 6> tc = p.weight * test * resp.tangent;
    for (int a = 0; a < static_cast<int>(p.support.size()); ++a) {
      const Eigen::Matrix3d blk = tc * b_block(p.dphi.col(a));
      for (int rr = 0; rr < 3; ++rr)
        for (int cc = 0; cc < 3; ++cc) trip.emplace_back(3 * p.test_node + rr, 3 * p.support[a] + cc, blk(rr, cc));
    }
  };
  for (size_t q = 0; q < volume_.size(); ++q) add_point(volume_[q], q, false);
  for (size_t q = 0; q < reaction_.size(); ++q) add_point(reaction_[q], volume_.size() + q, true);
  const double s = problem_.load_scale ? problem_.load_scale(time) : 1.0;
  for (const LocalIntegrationPoint& p : traction_)
    r->segment<3>(3 * p.test_node) -= s * p.weight * p.v * problem_.traction(p.x);
  for (int i = 0; i < n; ++i) {
    if (!constrained_[i]) continue;
    const Eigen::Vector3d ubar = problem_.prescribed_displacement(problem_.nodes.row(i).transpose());
    r->segment<3>(3 * i) = constraint_scale_ * (u_.segment<3>(3 * i) - ubar);
    for (int c = 0; c < 3; ++c) trip.emplace_back(3 * i + c, 3 * i + c, constraint_scale_);
  }
  k->resize(3 * n, 3 * n);
  k->setFromTriplets(trip.begin(), trip.end());
}

void LrpimModel::run(const std::function<void(const LrpimModel&, const LrpimStepRecord&)>& on_step) {
  const int n = statistics_.num_nodes;
  // The external load's size, for the relative stopping test.
  double f_ext = 0.0;
  {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * n);
    for (const LocalIntegrationPoint& p : traction_) f.segment<3>(3 * p.test_node) += p.weight * p.v * problem_.traction(p.x);
    f_ext = f.norm();
  }
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  bool analysed = false;
  Eigen::SparseMatrix<double> k;
  Eigen::VectorXd r;
  std::vector<core::KelvinState> trial;
  for (double t_new : problem_.step_times) {
    const double dt = t_new - time_;
    if (dt < 0.0) throw std::invalid_argument("LrpimModel: step times must not decrease");
    for (int i = 0; i < n; ++i)
      if (constrained_[i]) u_.segment<3>(3 * i) = problem_.prescribed_displacement(problem_.nodes.row(i).transpose());
    LrpimStepRecord rec;
    rec.time = t_new;
    double reference = f_ext;
    for (int it = 0;; ++it) {
      auto ta = Clock::now();
      assemble(t_new, dt, &k, &r, &trial);
      statistics_.assembly_seconds += seconds_since(ta);
      const double rn = r.norm();
      if (it == 0) reference = std::max(reference, rn);
      rec.residual = reference > 0.0 ? rn / reference : rn;
      if (rn <= 1e-10 * reference || reference == 0.0) break;
      if (it == 25) {
        std::ostringstream s;
        s << "LrpimModel '" << problem_.name << "': Newton did not converge at t = " << t_new
          << " s (relative residual " << rec.residual << " after 25 iterations); shorten the steps or the load";
        throw std::runtime_error(s.str());
      }
      auto ts = Clock::now();
      k.makeCompressed();
      if (!analysed) lu.analyzePattern(k), analysed = true;
      lu.factorize(k);
      if (lu.info() != Eigen::Success)
        throw std::runtime_error("LrpimModel '" + problem_.name + "': the tangent is singular (SparseLU: " +
                                 lu.lastErrorMessage() + "); check that the body is held (a displacement face)");
      u_ -= lu.solve(r);
      statistics_.solve_seconds += seconds_since(ts);
      rec.newton_iterations = it + 1;
    }
    states_ = trial;
    time_ = t_new;
    steps_.push_back(rec);
    if (on_step) on_step(*this, rec);
  }
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
