#include "meshless/surrogate/surrogate_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>

namespace meshless {

ScaledLeastSquares::ScaledLeastSquares(const Eigen::MatrixXd& a, double rank_threshold)
    : inverse_scale_(a.cols()), rows_(a.rows()) {
  if (!(rank_threshold > 0.0 && rank_threshold < 1.0))
    throw std::invalid_argument("ScaledLeastSquares: the rank threshold must be in (0, 1)");
  if (!a.allFinite())
    throw std::invalid_argument("ScaledLeastSquares: the design matrix has a non-finite entry");
  Eigen::MatrixXd scaled = a;
  for (Eigen::Index k = 0; k < a.cols(); ++k) {
    const double norm = a.col(k).norm();
    inverse_scale_[k] = norm > 0.0 ? 1.0 / norm : 0.0;
    scaled.col(k) *= inverse_scale_[k];
  }
  if (a.rows() == 0 || a.cols() == 0) return;
  qr_.compute(scaled);
  // The leading pivots above the threshold: with column pivoting |R_kk| does not increase along the diagonal,
  // so the first one at or below it ends the columns the data can determine. Eigen's own rank() counts every
  // pivot above the threshold but its solve() ignores the threshold, hence this count and solve() below.
  const Eigen::MatrixXd& r = qr_.matrixQR();
  const double largest = std::abs(r(0, 0));
  while (rank_ < qr_.nonzeroPivots() && std::abs(r(rank_, rank_)) > rank_threshold * largest) ++rank_;
}

Eigen::MatrixXd ScaledLeastSquares::solve(const Eigen::MatrixXd& b) const {
  if (b.rows() != rows_)
    throw std::invalid_argument(
        fmt::format("ScaledLeastSquares::solve: {} rows expected, {} given", rows_, b.rows()));
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(cols(), b.cols());
  if (rank_ == 0) return x;
  // Q^T b: the reflectors beyond the rank do not touch its first rank_ rows.
  Eigen::MatrixXd c = b;
  c.applyOnTheLeft(qr_.householderQ().setLength(rank_).adjoint());
  const Eigen::MatrixXd y =
      qr_.matrixQR().topLeftCorner(rank_, rank_).triangularView<Eigen::Upper>().solve(c.topRows(rank_));
  const auto& permutation = qr_.colsPermutation().indices();
  for (Eigen::Index i = 0; i < rank_; ++i)
    x.row(permutation[i]) = y.row(i) * inverse_scale_[permutation[i]];  // back to the unscaled columns
  return x;
}

namespace {

const char* const kAxis = "xyz";

/// The summary of a fit whose data all lie below the noise floor: zero coefficients, nothing solved.
FitSummary below_noise_floor(std::string what, const Eigen::VectorXd& b, int parameters) {
  FitSummary f;
  f.what = std::move(what);
  f.termination = "BELOW_NOISE_FLOOR";
  f.usable = true;
  f.initial_cost = f.final_cost = 0.5 * b.squaredNorm();
  f.num_residuals = static_cast<int>(b.size());
  f.num_parameters = parameters;
  f.rank = 0;
  return f;
}

/// min |A c - b| through `ls` (the factorisation of A), or c = 0 when every value of b is at most
/// `noise_floor` (b is in units of the axis' largest displacement). Never fails.
Eigen::VectorXd fit_linear(const ScaledLeastSquares& ls, const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                           double noise_floor, std::string what, FitSummary* summary) {
  if (b.size() == 0 || b.cwiseAbs().maxCoeff() <= noise_floor) {
    *summary = below_noise_floor(std::move(what), b, static_cast<int>(a.cols()));
    return Eigen::VectorXd::Zero(a.cols());
  }
  const Eigen::VectorXd c = ls.solve(b);
  FitSummary& f = *summary;
  f = FitSummary{};
  f.what = std::move(what);
  f.termination = "SOLVED";
  f.usable = true;
  f.initial_cost = 0.5 * b.squaredNorm();
  f.final_cost = 0.5 * (a * c - b).squaredNorm();
  f.num_residuals = static_cast<int>(b.size());
  f.num_parameters = static_cast<int>(a.cols());
  f.rank = ls.rank();
  return c;
}

double polynomial(const Eigen::VectorXd& r, double s) {
  double sum = 0.0, power = s;
  for (Eigen::Index p = 0; p < r.size(); ++p, power *= s) sum += r[p] * power;
  return sum;
}

/// The smallest candidate (in the order given: fewest coefficients first) whose cross-validation error is
/// within kParsimony of the best one, or below the noise floor (`noise_floor` of the data's scale, where two
/// errors cannot be told apart): a larger model must earn its coefficients.
constexpr double kParsimony = 0.01;
std::size_t most_parsimonious(const std::vector<CvScore>& scores, double data_scale, double noise_floor) {
  double best = std::numeric_limits<double>::infinity();
  for (const CvScore& s : scores) best = std::min(best, s.rms);
  const double good_enough = std::max((1.0 + kParsimony) * best, noise_floor * data_scale);
  for (std::size_t i = 0; i < scores.size(); ++i)
    if (scores[i].rms <= good_enough) return i;
  return 0;
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
/// the fit on every level. The fits are linear least squares in the coefficients r_ip (ScaledLeastSquares).
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
      std::vector<int> train;
      for (int l = 0; l < n; ++l)
        if (fold[l] != f) {
          st.push_back(s[l]);
          train.push_back(l);
        }
      Eigen::MatrixXd ut(train.size(), 3);  // scaled units
      for (std::size_t r = 0; r < train.size(); ++r) ut.row(r) = u[train[r]].transpose() / u_scale;
      const Eigen::MatrixXd r = ScaledLeastSquares(force_powers(st, order), options.rank_threshold).solve(ut);
      for (int l = 0; l < n; ++l)
        if (fold[l] == f)
          for (int i = 0; i < 3; ++i) sq += std::pow(u_scale * polynomial(r.col(i), s[l]) - u[l][i], 2);
    }
    out->force_order_cv.push_back({order, 0, 0, 0, std::sqrt(sq / n)});
  }
  if (!out->force_order_cv.empty()) {
    const std::size_t pick = most_parsimonious(out->force_order_cv, u_scale, options.noise_floor);
    out->force_order = out->force_order_cv[pick].force_order;
    out->contact_cv_rms = out->force_order_cv[pick].rms;
  }
  if (out->force_order == 0)
    throw std::invalid_argument(
        fmt::format("cross-validation of eqs. 25-27 needs more force levels than {} with {} folds; "
                    "raise surrogate.force_levels or lower surrogate.cv_folds",
                    n, k));
  const Eigen::MatrixXd v = force_powers(s, out->force_order);
  const ScaledLeastSquares ls(v, options.rank_threshold);
  out->contact.resize(3, out->force_order);
  for (int i = 0; i < 3; ++i) {
    Eigen::VectorXd ui(n);
    for (int l = 0; l < n; ++l) ui[l] = u[l][i] / u_scale;
    FitSummary summary;
    const Eigen::VectorXd r =
        fit_linear(ls, v, ui, options.noise_floor,
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
      const ScaledLeastSquares ls(force_powers(st, order), options.rank_threshold);
      const Eigen::MatrixXd vh = force_powers(sh, order);
      for (int i = 0; i < 3; ++i) {
        Eigen::MatrixXd yt(train.size(), ns), yh(test.size(), ns);
        for (std::size_t r = 0; r < train.size(); ++r) yt.row(r) = target[i].col(train[r]).transpose();
        for (std::size_t r = 0; r < test.size(); ++r) yh.row(r) = target[i].col(test[r]).transpose();
        sq += (vh * ls.solve(yt) - yh).squaredNorm();
      }
    }
    out->field_order_cv.push_back({order, 0, 0, 0, u_scale * std::sqrt(sq / (static_cast<double>(ns) * n))});
  }
  if (out->field_order_cv.empty())
    throw std::invalid_argument(
        "cross-validation of eq. 28 needs more force levels; raise surrogate.force_levels");
  const std::size_t pick = most_parsimonious(out->field_order_cv, u_scale, options.noise_floor);
  out->field_order = out->field_order_cv[pick].force_order;
  out->field_order_cv_rms = out->field_order_cv[pick].rms;
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
  if (!(noise_floor >= 0.0 && noise_floor < 1.0)) return fail("noise_floor must be in [0, 1)");
  if (!(rank_threshold > 0.0 && rank_threshold < 1.0)) return fail("rank_threshold must be in (0, 1)");
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
      if (d.rows() != ns)
        throw std::invalid_argument("fit_contact: a displacement field has the wrong size");
      else if (!d.allFinite())
        throw std::invalid_argument(fmt::format(
            "fit_contact: the training displacements of axis {} hold a non-finite value; the full model's "
            "solve did not converge, check its Newton iterations in the training lines",
            kAxis[j]));
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

  // Per axis: eqs. 25-27 at the contact node, the force order of eq. 28, and stage 1, every node's
  // least-squares force polynomial (eqs. 25-27 at each node) in scaled units. With the Kronecker design
  // psi (x) V, the joint least-squares fit of eq. 28 is psi^+ D V^+T: stage 1, then stage 2 below.
  struct AxisData {
    double u_scale = 1.0;                   ///< [m] the axis' largest trained displacement
    Eigen::MatrixXd v;                      ///< L by field order: the force powers
    std::array<Eigen::MatrixXd, 3> target;  ///< per component: #S by L, scaled data
    std::array<Eigen::MatrixXd, 3> nodal;   ///< per component: #S by field order
    std::array<bool, 3> noise{};            ///< the component's data all lie below the noise floor
  };
  std::array<AxisData, 3> axes;
  for (int j = 0; j < 3; ++j) {
    AxisFit& axis = out.axis[j];
    AxisData& ad = axes[j];
    ad.u_scale = 0.0;
    for (const core::PointMatrix& d : data.displacement[j])
      ad.u_scale = std::max(ad.u_scale, d.cwiseAbs().maxCoeff());
    if (!(ad.u_scale > 0.0)) ad.u_scale = 1.0;  // no response at all: every fit below is exactly zero

    std::vector<Eigen::Vector3d> uc(nl);
    for (int l = 0; l < nl; ++l) uc[l] = data.displacement[j][l].row(data.contact).transpose();
    fit_contact_node(s, uc, ad.u_scale, max_force, j, options, &axis, &out.summaries);

    for (int i = 0; i < 3; ++i) {
      ad.target[i].resize(ns, nl);
      for (int l = 0; l < nl; ++l) ad.target[i].col(l) = data.displacement[j][l].col(i) / ad.u_scale;
      ad.noise[i] = ad.target[i].cwiseAbs().maxCoeff() <= options.noise_floor;
    }
    choose_field_order(s, ad.target, ad.u_scale, options, &axis);
    ad.v = force_powers(s, axis.field_order);
    const ScaledLeastSquares vls(ad.v, options.rank_threshold);
    for (int i = 0; i < 3; ++i) ad.nodal[i] = vls.solve(ad.target[i].transpose()).transpose();
  }

  // Stage 2 cross-validation of (a, b, c) for every axis and component, in closed form: one factorisation per
  // fold and candidate serves the nine (the basis depends on the surface nodes only).
  std::array<std::array<std::vector<double>, 3>, 3> sq;  // [axis][component][candidate]
  for (auto& axis_sq : sq)
    for (auto& component_sq : axis_sq) component_sq.assign(candidates.size(), 0.0);
  for (int f = 0; f < k; ++f) {
    const Eigen::MatrixXd psi_train = rows_where(psi, fold, f, false);
    const Eigen::MatrixXd psi_test = rows_where(psi, fold, f, true);
    std::array<std::array<Eigen::MatrixXd, 3>, 3> nodal_train, target_test;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        nodal_train[j][i] = rows_where(axes[j].nodal[i], fold, f, false);
        target_test[j][i] = rows_where(axes[j].target[i], fold, f, true);
      }
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const ScaledLeastSquares ls(columns(psi_train, candidates[c].cols), options.rank_threshold);
      const Eigen::MatrixXd test_basis = columns(psi_test, candidates[c].cols);
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const Eigen::MatrixXd predicted =  // held-out nodes by levels
              test_basis * ls.solve(nodal_train[j][i]) * axes[j].v.transpose();
          sq[j][i][c] += (predicted - target_test[j][i]).squaredNorm();
        }
    }
  }

  // The fits themselves: on every surface node, one linear least-squares problem per force power, the
  // factorisation of each chosen basis shared by the components and axes that chose it.
  std::map<std::size_t, ScaledLeastSquares> factorised;
  for (int j = 0; j < 3; ++j) {
    AxisFit& axis = out.axis[j];
    const AxisData& ad = axes[j];
    const int order = axis.field_order;
    const Eigen::MatrixXd sigma_powers = force_powers(data.levels, order);  // L by order, sigma in N
    Eigen::MatrixXd reconstructed_sq = Eigen::MatrixXd::Zero(ns, nl);
    for (int i = 0; i < 3; ++i) {
      InducedFieldFit& field = axis.field[i];
      for (std::size_t c = 0; c < candidates.size(); ++c)
        field.grid.push_back({order, candidates[c].a, candidates[c].b, candidates[c].c,
                              ad.u_scale * std::sqrt(sq[j][i][c] / (static_cast<double>(ns) * nl))});
      // A component of noise (an x force's response across a symmetric body, say) is zero, with the
      // smallest basis (candidates[0], the constant): nothing to choose, nothing to fit.
      const std::size_t best =
          ad.noise[i] ? 0 : most_parsimonious(field.grid, ad.u_scale, options.noise_floor);
      field.tangential_order = candidates[best].a;
      field.normal_order = candidates[best].b;
      field.contact_order = candidates[best].c;
      field.cv_rms = field.grid[best].rms;

      const Eigen::MatrixXd basis = columns(psi, candidates[best].cols);
      auto it = factorised.find(best);
      if (it == factorised.end())
        it = factorised.emplace(best, ScaledLeastSquares(basis, options.rank_threshold)).first;
      field.coefficients.resize(basis.cols(), order);
      for (int p = 0; p < order; ++p) {
        const std::string what =
            fmt::format("eq. 28 axis {} component {} power {}", kAxis[j], kAxis[i], p + 1);
        FitSummary summary;
        Eigen::VectorXd c;
        if (ad.noise[i]) {
          summary = below_noise_floor(what, ad.nodal[i].col(p), static_cast<int>(basis.cols()));
          c = Eigen::VectorXd::Zero(basis.cols());
        } else {
          c = fit_linear(it->second, basis, ad.nodal[i].col(p), options.noise_floor, what, &summary);
        }
        out.summaries.push_back(summary);
        field.coefficients.col(p) = c * ad.u_scale / std::pow(max_force, p + 1);
      }
      // Reconstruction over the training data in SI: u_i(X_s, sigma_l) = psi_s . C sigma_l powers.
      const Eigen::MatrixXd u_fit = basis * field.coefficients * sigma_powers.transpose();
      reconstructed_sq += (u_fit - ad.target[i] * ad.u_scale).cwiseAbs2();
    }
    axis.training_rms = std::sqrt(reconstructed_sq.sum() / (static_cast<double>(ns) * nl));
  }
  return out;
}

Eigen::MatrixXd force_powers(const std::vector<double>& s, int order) {
  Eigen::MatrixXd v(s.size(), order);
  for (std::size_t l = 0; l < s.size(); ++l) {
    double power = s[l];
    for (int p = 0; p < order; ++p, power *= s[l]) v(l, p) = power;
  }
  return v;
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
