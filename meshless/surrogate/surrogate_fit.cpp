#include "meshless/surrogate/surrogate_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

#include "meshless/surrogate/surrogate_cost_functions.hpp"

namespace meshless {
namespace {

const char* const kAxis = "xyz";

ceres::Solver::Options solver_options(const SurrogateFitOptions& o) {
  ceres::Solver::Options s;
  s.minimizer_type = ceres::TRUST_REGION;
  s.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  s.linear_solver_type = ceres::DENSE_QR;
  s.max_num_iterations = o.max_num_iterations;
  s.function_tolerance = o.function_tolerance;
  s.gradient_tolerance = o.gradient_tolerance;
  s.parameter_tolerance = o.parameter_tolerance;
  s.logging_type = ceres::SILENT;
  s.minimizer_progress_to_stdout = false;
  s.num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return s;
}

FitSummary summarise(std::string what, const ceres::Solver::Summary& s) {
  FitSummary f;
  f.what = std::move(what);
  f.termination = ceres::TerminationTypeToString(s.termination_type);
  f.usable = s.IsSolutionUsable();
  f.iterations = static_cast<int>(s.iterations.size());
  f.initial_cost = s.initial_cost;
  f.final_cost = s.final_cost;
  f.num_residuals = s.num_residuals;
  f.num_parameters = s.num_parameters;
  return f;
}

/// Throws when Ceres did not produce a usable solution, with its own report and what to change.
void require_usable(const FitSummary& f, const ceres::Solver::Summary& s) {
  if (f.usable && s.termination_type != ceres::FAILURE) return;
  throw std::runtime_error(
      fmt::format("the Levenberg-Marquardt fit of {} failed ({}: {}); lower surrogate.max_force_order or "
                  "surrogate.max_tangential_order / max_normal_order",
                  f.what, f.termination, s.message));
}

/// Eqs. 25-27 for one component by Ceres LM: the coefficients r_1..r_order of s^1..s^order (scaled units).
Eigen::VectorXd fit_force_polynomial(const std::vector<double>& s, const std::vector<double>& u, int order,
                                     const SurrogateFitOptions& options, const std::string& what,
                                     FitSummary* summary) {
  std::vector<double> r(order, 0.0);
  ceres::Problem problem;
  for (std::size_t l = 0; l < s.size(); ++l)
    problem.AddResidualBlock(ForcePolynomialResidual::Create(s[l], u[l], order), nullptr, r.data());
  ceres::Solver::Options so = solver_options(options);
  so.num_threads = 1;
  ceres::Solver::Summary cs;
  ceres::Solve(so, &problem, &cs);
  const FitSummary f = summarise(what, cs);
  require_usable(f, cs);
  if (summary) *summary = f;
  return Eigen::Map<Eigen::VectorXd>(r.data(), order);
}

double polynomial(const Eigen::VectorXd& r, double s) {
  double sum = 0.0, power = s;
  for (Eigen::Index p = 0; p < r.size(); ++p, power *= s) sum += r[p] * power;
  return sum;
}

/// The smallest candidate (in the order given: fewest coefficients first) whose cross-validation error is
/// within kParsimony of the best one, or at round-off level (kRoundOff of the data's scale): a larger model
/// must earn its coefficients.
constexpr double kParsimony = 0.01;
constexpr double kRoundOff = 1e-10;
std::size_t most_parsimonious(const std::vector<CvScore>& scores, double data_scale) {
  double best = std::numeric_limits<double>::infinity();
  for (const CvScore& s : scores) best = std::min(best, s.rms);
  const double good_enough = std::max((1.0 + kParsimony) * best, kRoundOff * data_scale);
  for (std::size_t i = 0; i < scores.size(); ++i)
    if (scores[i].rms <= good_enough) return i;
  return 0;
}

/// L by order matrix of s_l^p, p = 1..order (no constant: u(0) = 0).
Eigen::MatrixXd force_powers(const std::vector<double>& s, int order) {
  Eigen::MatrixXd v(s.size(), order);
  for (std::size_t l = 0; l < s.size(); ++l) {
    double power = s[l];
    for (int p = 0; p < order; ++p, power *= s[l]) v(l, p) = power;
  }
  return v;
}

/// Deterministic partition of n items into k folds: a seeded Fisher-Yates permutation dealt round-robin.
std::vector<int> node_folds(int n, int k, unsigned seed) {
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::mt19937 rng(seed);
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[rng() % static_cast<unsigned>(i + 1)]);
  std::vector<int> fold(n);
  for (int i = 0; i < n; ++i) fold[order[i]] = i % k;
  return fold;
}

/// Rows of m selected by a mask.
Eigen::MatrixXd rows_where(const Eigen::MatrixXd& m, const std::vector<int>& fold, int f, bool equal) {
  int count = 0;
  for (int v : fold) count += (v == f) == equal;
  Eigen::MatrixXd out(count, m.cols());
  int row = 0;
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    if ((fold[i] == f) == equal) out.row(row++) = m.row(i);
  return out;
}

Eigen::MatrixXd columns(const Eigen::MatrixXd& m, const std::vector<int>& cols) {
  Eigen::MatrixXd out(m.rows(), cols.size());
  for (std::size_t c = 0; c < cols.size(); ++c) out.col(c) = m.col(cols[c]);
  return out;
}

/// The contact node's eqs. 25-27 on one axis: lambda by k-fold cross-validation over the force levels, then
/// the fit on every level.
void fit_contact_node(const std::vector<double>& s, const std::vector<Eigen::Vector3d>& u, double u_scale,
                      double max_force, int axis, const SurrogateFitOptions& options, AxisFit* out,
                      std::vector<FitSummary>* summaries) {
  const int n = static_cast<int>(s.size());
  const int k = std::min(options.cv_folds, n);
  std::vector<int> fold(n);
  for (int l = 0; l < n; ++l) fold[l] = l % k;  // levels in increasing order, dealt round-robin
  const int largest_fold = (n + k - 1) / k;
  for (int order = 1; order <= std::min(options.max_force_order, n - largest_fold); ++order) {
    double sq = 0.0;
    for (int f = 0; f < k; ++f) {
      std::vector<double> st;
      std::array<std::vector<double>, 3> ut;
      for (int l = 0; l < n; ++l)
        if (fold[l] != f) {
          st.push_back(s[l]);
          for (int i = 0; i < 3; ++i) ut[i].push_back(u[l][i] / u_scale);
        }
      for (int i = 0; i < 3; ++i) {
        const Eigen::VectorXd r =
            fit_force_polynomial(st, ut[i], order, options, "cross-validation", nullptr);
        for (int l = 0; l < n; ++l)
          if (fold[l] == f) sq += std::pow(u_scale * polynomial(r, s[l]) - u[l][i], 2);
      }
    }
    out->force_order_cv.push_back({order, 0, 0, 0, std::sqrt(sq / n)});
  }
  if (!out->force_order_cv.empty()) {
    const std::size_t pick = most_parsimonious(out->force_order_cv, u_scale);
    out->force_order = out->force_order_cv[pick].force_order;
    out->contact_cv_rms = out->force_order_cv[pick].rms;
  }
  if (out->force_order == 0)
    throw std::runtime_error(
        fmt::format("cross-validation of eqs. 25-27 needs more force levels than {} with {} folds; "
                    "raise surrogate.force_levels or lower surrogate.cv_folds",
                    n, k));
  out->contact.resize(3, out->force_order);
  for (int i = 0; i < 3; ++i) {
    std::vector<double> ui(n);
    for (int l = 0; l < n; ++l) ui[l] = u[l][i] / u_scale;
    FitSummary summary;
    const Eigen::VectorXd r =
        fit_force_polynomial(s, ui, out->force_order, options,
                             fmt::format("eqs. 25-27 axis {} component {}", kAxis[axis], kAxis[i]), &summary);
    summaries->push_back(summary);
    for (int p = 0; p < out->force_order; ++p)
      out->contact(i, p) = r[p] * u_scale / std::pow(max_force, p + 1);
  }
}

/// The force order of eq. 28 by k-fold cross-validation over the levels (the same folds as eqs. 25-27), every
/// surface node and component at once, in closed form (linear least squares).
void choose_field_order(const std::vector<double>& s, const std::array<Eigen::MatrixXd, 3>& target,
                        double u_scale, const SurrogateFitOptions& options, AxisFit* out) {
  const int n = static_cast<int>(s.size());
  const int k = std::min(options.cv_folds, n);
  const int largest_fold = (n + k - 1) / k;
  const Eigen::Index ns = target[0].rows();
  for (int order = 1; order <= std::min(options.max_force_order, n - largest_fold); ++order) {
    double sq = 0.0;
    for (int f = 0; f < k; ++f) {
      std::vector<double> st, sh;
      std::vector<int> train, test;
      for (int l = 0; l < n; ++l) {
        (l % k == f ? sh : st).push_back(s[l]);
        (l % k == f ? test : train).push_back(l);
      }
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(force_powers(st, order));
      const Eigen::MatrixXd vh = force_powers(sh, order);
      for (int i = 0; i < 3; ++i) {
        Eigen::MatrixXd yt(train.size(), ns), yh(test.size(), ns);
        for (std::size_t r = 0; r < train.size(); ++r) yt.row(r) = target[i].col(train[r]).transpose();
        for (std::size_t r = 0; r < test.size(); ++r) yh.row(r) = target[i].col(test[r]).transpose();
        sq += (vh * qr.solve(yt) - yh).squaredNorm();
      }
    }
    out->field_order_cv.push_back({order, 0, 0, 0, u_scale * std::sqrt(sq / (static_cast<double>(ns) * n))});
  }
  if (out->field_order_cv.empty())
    throw std::runtime_error(
        "cross-validation of eq. 28 needs more force levels; raise surrogate.force_levels");
  const std::size_t pick = most_parsimonious(out->field_order_cv, u_scale);
  out->field_order = out->field_order_cv[pick].force_order;
  out->field_order_cv_rms = out->field_order_cv[pick].rms;
}

/// Eq. 28's spatial fit of one power's per-node coefficients by Ceres LM: min sum_s (psi(X_s) . c -
/// target_s)^2.
Eigen::VectorXd fit_spatial(const Eigen::MatrixXd& psi, const Eigen::VectorXd& target,
                            const SurrogateFitOptions& options, const std::string& what,
                            FitSummary* summary) {
  const int nb = static_cast<int>(psi.cols());
  std::vector<double> c(nb, 0.0);
  ceres::Problem problem;
  for (Eigen::Index s = 0; s < psi.rows(); ++s) {
    std::vector<double> basis(nb);
    for (int k = 0; k < nb; ++k) basis[k] = psi(s, k);
    problem.AddResidualBlock(InducedFieldResidual::Create(std::move(basis), target[s]), nullptr, c.data());
  }
  ceres::Solver::Summary cs;
  ceres::Solve(solver_options(options), &problem, &cs);
  *summary = summarise(what, cs);
  require_usable(*summary, cs);
  return Eigen::Map<Eigen::VectorXd>(c.data(), nb);
}

}  // namespace

bool SurrogateFitOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (max_force_order < 1 || max_force_order > 8) return fail("max_force_order must be in [1, 8]");
  if (max_tangential_order < 0 || max_tangential_order > 12)
    return fail("max_tangential_order must be in [0, 12]");
  if (max_normal_order < 0 || max_normal_order > 8) return fail("max_normal_order must be in [0, 8]");
  if (max_contact_order < 0 || max_contact_order > 6) return fail("max_contact_order must be in [0, 6]");
  if (max_contact_order > 0 && !(contact_length > 0.0))
    return fail("contact_length must be > 0 with contact terms");
  if (cv_folds < 2) return fail("cv_folds must be >= 2");
  if (max_num_iterations < 1) return fail("max_num_iterations must be >= 1");
  if (!(function_tolerance >= 0.0) || !(gradient_tolerance >= 0.0) || !(parameter_tolerance >= 0.0))
    return fail("the Ceres tolerances must be >= 0");
  return true;
}

ContactFit fit_contact(const SurfaceNodes& surface, const ContactTrainingData& data, double max_force,
                       const SurrogateFitOptions& options) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw std::invalid_argument("SurrogateFitOptions: " + invalid);
  if (!(max_force > 0.0)) throw std::invalid_argument("fit_contact: max_force must be > 0");
  const int ns = surface.size();
  const int nl = static_cast<int>(data.levels.size());
  for (int j = 0; j < 3; ++j) {
    if (static_cast<int>(data.displacement[j].size()) != nl)
      throw std::invalid_argument("fit_contact: one displacement field per level and axis expected");
    for (const core::PointMatrix& d : data.displacement[j])
      if (d.rows() != ns) throw std::invalid_argument("fit_contact: a displacement field has the wrong size");
  }
  std::vector<double> s(nl);
  for (int l = 0; l < nl; ++l) s[l] = data.levels[l] / max_force;
  if (!std::is_sorted(data.levels.begin(), data.levels.end()))
    throw std::invalid_argument("fit_contact: levels must be increasing");

  ContactFit out;
  out.contact = data.contact;
  const Eigen::Vector3d xc = surface.position.row(data.contact).transpose();
  double length = 0.0;
  for (int i = 0; i < ns; ++i) length = std::max(length, (surface.position.row(i).transpose() - xc).norm());
  out.frame = SurfaceFrame::at(xc, surface.normal.row(data.contact).transpose(), length,
                               options.contact_length > 0.0 ? options.contact_length : length);
  const SpatialBasis full(options.max_tangential_order, options.max_normal_order, options.max_contact_order,
                          out.frame.contact_length / length);
  Eigen::MatrixX3d local(ns, 3);
  for (int i = 0; i < ns; ++i)
    local.row(i) = out.frame.local(surface.position.row(i).transpose()).transpose();
  const Eigen::MatrixXd psi = full.evaluate(local);  // #S by #basis at the largest orders

  // Spatial folds: every candidate (a, b) is scored on the same partition of the surface nodes.
  const int k = std::min(options.cv_folds, ns);
  const std::vector<int> fold = node_folds(ns, k, options.cv_seed);
  struct Candidate {
    int a, b, c;
    std::vector<int> cols;
  };
  std::vector<Candidate> candidates;
  const int smallest_training = ns - (ns + k - 1) / k;
  for (int a = 0; a <= options.max_tangential_order; ++a)
    for (int b = 0; b <= options.max_normal_order; ++b)
      for (int c = 0; c <= options.max_contact_order; ++c) {
        std::vector<int> cols = full.subset(a, b, c);
        if (2 * static_cast<int>(cols.size()) <= smallest_training)
          candidates.push_back({a, b, c, std::move(cols)});
      }
  if (candidates.empty())
    throw std::invalid_argument(
        fmt::format("fit_contact: {} surface nodes are too few for {}-fold cross-validation", ns, k));
  // Fewest coefficients first, so that most_parsimonious() prefers the smaller of two equally good surfaces.
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.cols.size() < y.cols.size(); });

  for (int j = 0; j < 3; ++j) {
    AxisFit& axis = out.axis[j];
    double u_scale = 0.0;
    for (const core::PointMatrix& d : data.displacement[j])
      u_scale = std::max(u_scale, d.cwiseAbs().maxCoeff());
    if (!(u_scale > 0.0)) u_scale = 1.0;

    std::vector<Eigen::Vector3d> uc(nl);
    for (int l = 0; l < nl; ++l) uc[l] = data.displacement[j][l].row(data.contact).transpose();
    fit_contact_node(s, uc, u_scale, max_force, j, options, &axis, &out.summaries);

    std::array<Eigen::MatrixXd, 3> target;  // per component: #S by L, scaled data
    for (int i = 0; i < 3; ++i) {
      target[i].resize(ns, nl);
      for (int l = 0; l < nl; ++l) target[i].col(l) = data.displacement[j][l].col(i) / u_scale;
    }
    choose_field_order(s, target, u_scale, options, &axis);
    const int order = axis.field_order;

    // Stage 1: every node's least-squares force polynomial (eqs. 25-27 at each node), in scaled units. With
    // the Kronecker design psi (x) V, the joint least-squares fit of eq. 28 is psi^+ D V^+T: this stage, then
    // stage 2.
    const Eigen::MatrixXd v = force_powers(s, order);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> vqr(v);
    std::array<Eigen::MatrixXd, 3> nodal;  // per component: #S by order
    for (int i = 0; i < 3; ++i) nodal[i] = vqr.solve(target[i].transpose()).transpose();

    // Stage 2 cross-validation of (a, b) per component, in closed form (the same linear least-squares problem
    // that Ceres solves below; a QR per fold and candidate serves the three components).
    std::array<std::vector<double>, 3> sq;
    for (int i = 0; i < 3; ++i) sq[i].assign(candidates.size(), 0.0);
    for (int f = 0; f < k; ++f) {
      const Eigen::MatrixXd psi_train = rows_where(psi, fold, f, false);
      const Eigen::MatrixXd psi_test = rows_where(psi, fold, f, true);
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(columns(psi_train, candidates[c].cols));
        const Eigen::MatrixXd test_basis = columns(psi_test, candidates[c].cols);
        for (int i = 0; i < 3; ++i) {
          const Eigen::MatrixXd coeff = qr.solve(rows_where(nodal[i], fold, f, false));
          const Eigen::MatrixXd predicted = test_basis * coeff * v.transpose();  // held-out nodes by levels
          sq[i][c] += (predicted - rows_where(target[i], fold, f, true)).squaredNorm();
        }
      }
    }
    Eigen::MatrixXd reconstructed_sq = Eigen::MatrixXd::Zero(ns, nl);
    for (int i = 0; i < 3; ++i) {
      InducedFieldFit& field = axis.field[i];
      for (std::size_t c = 0; c < candidates.size(); ++c)
        field.grid.push_back({order, candidates[c].a, candidates[c].b, candidates[c].c,
                              u_scale * std::sqrt(sq[i][c] / (static_cast<double>(ns) * nl))});
      const std::size_t best = most_parsimonious(field.grid, u_scale);
      field.tangential_order = candidates[best].a;
      field.normal_order = candidates[best].b;
      field.contact_order = candidates[best].c;
      field.cv_rms = field.grid[best].rms;

      // The fit itself: Ceres LM on every surface node, one problem per force power.
      const Eigen::MatrixXd basis = columns(psi, candidates[best].cols);
      field.coefficients.resize(basis.cols(), order);
      for (int p = 0; p < order; ++p) {
        FitSummary summary;
        const Eigen::VectorXd c = fit_spatial(
            basis, nodal[i].col(p), options,
            fmt::format("eq. 28 axis {} component {} power {}", kAxis[j], kAxis[i], p + 1), &summary);
        out.summaries.push_back(summary);
        field.coefficients.col(p) = c * u_scale / std::pow(max_force, p + 1);
      }
      // Reconstruction over the training data in SI: u_i(X_s, sigma_l) = psi_s . C sigma_l powers.
      const Eigen::MatrixXd sigma_powers = force_powers(data.levels, order);  // L by order, sigma in N
      const Eigen::MatrixXd u_fit = basis * field.coefficients * sigma_powers.transpose();
      reconstructed_sq += (u_fit - target[i] * u_scale).cwiseAbs2();
    }
    axis.training_rms = std::sqrt(reconstructed_sq.sum() / (static_cast<double>(ns) * nl));
  }
  return out;
}

Eigen::MatrixXd nodal_coefficients(const SurfaceNodes& surface, const SurfaceFrame& frame,
                                   const AxisFit& axis) {
  const int ns = surface.size();
  Eigen::MatrixXd out(3 * ns, axis.field_order);
  for (int i = 0; i < 3; ++i) {
    const InducedFieldFit& field = axis.field[i];
    const SpatialBasis basis(field.tangential_order, field.normal_order, field.contact_order,
                             frame.contact_length / frame.length);
    if (basis.size() != field.coefficients.rows() || field.coefficients.cols() != axis.field_order)
      throw std::invalid_argument("nodal_coefficients: coefficient matrix does not match the orders");
    std::vector<double> psi(basis.size());
    for (int s = 0; s < ns; ++s) {
      basis.evaluate(frame.local(surface.position.row(s).transpose()), psi.data());
      out.row(3 * s + i) =
          Eigen::Map<const Eigen::RowVectorXd>(psi.data(), basis.size()) * field.coefficients;
    }
  }
  return out;
}

}  // namespace meshless
