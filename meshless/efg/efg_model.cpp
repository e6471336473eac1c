#include "meshless/efg/efg_model.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "core/step_predictor.hpp"
#include "meshless/cut/cut_weights.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"
#include "meshless/parallel_for.hpp"
#include "meshless/solvers/anderson_acceleration.hpp"
#include "meshless/solvers/kept_factors.hpp"
#include "meshless/solvers/efg_linear_solver.hpp"

namespace meshless {

namespace {

/// Room kept in the matrix arrays of a cut body for the node pairs that local updates add (a fraction of the
/// entries): a 10 mm extension on configs/lung_large.json adds 46 node pairs (bench_cut) to a matrix of 22.8 M
/// entries (2.5 M pairs), so 1 % lasts for many updates without a new allocation.
constexpr double kSpareMatrixFraction = 0.01;

/// Spare slots kept in the shape-function tables of a cut body for the rows a local update evaluates again (a
/// fraction of the entries; the reused rows stay where they are, update_shape_functions). A 10 mm extension on
/// configs/lung_large.json evaluates about 4 % of the volume points again, so a quarter lasts for several steps of
/// an incision before the rows are packed into new arrays.
constexpr double kSpareTableFraction = 0.25;

/// Room kept in the per-point arrays of a cut body (strain, stress, tangent) for the points a local update adds: a
/// 10 mm extension on configs/lung_large.json adds about 500 of 200,000 volume points.
constexpr double kSparePointFraction = 0.05;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// B^T of eq. 22 for one node (3 by 6), gradient g = (phi_x, phi_y, phi_z).
inline Eigen::Matrix<double, 3, 6> b_transpose(const Eigen::Vector3d& g) {
  Eigen::Matrix<double, 3, 6> bt;
  bt << g.x(), 0.0, 0.0, g.y(), 0.0, g.z(),  //
      0.0, g.y(), 0.0, g.x(), g.z(), 0.0,     //
      0.0, 0.0, g.z(), 0.0, g.y(), g.x();
  return bt;
}

/// eq. 17: the engineering strain at point q of `table` for the nodal parameters u (the trial gradients, without VCI).
inline core::Vector6 strain_at(const ShapeTable& table, int q, const Eigen::VectorXd& u) {
  core::Vector6 e = core::Vector6::Zero();
  for (int s = table.begin(q); s < table.end(q); ++s) {
    const Eigen::Vector3d g = table.dphi.col(s);
    const Eigen::Vector3d us = u.segment<3>(3 * table.nodes[s]);
    e[0] += g.x() * us.x();
    e[1] += g.y() * us.y();
    e[2] += g.z() * us.z();
    e[3] += g.y() * us.x() + g.x() * us.y();
    e[4] += g.z() * us.y() + g.y() * us.z();
    e[5] += g.z() * us.x() + g.x() * us.z();
  }
  return e;
}

}  // namespace

EfgModel::EfgModel(EfgProblem problem, EfgOptions options)
    : problem_(std::move(problem)),
      options_(options),
      law_(problem_.material),
      mixing_(options_.anderson_depth) {
  // With k = 0 the tangent never changes: its exact LU, factorised once, ends every step in one Newton iteration,
  // where factors of its symmetric part would need several (and a patch test would stop at Newton's tolerance
  // instead of round-off).
  if (problem_.material.k == 0.0) options_.direct_symmetric_part = false;
  if (!(problem_.node_spacing > 0.0))
    throw std::invalid_argument(fmt::format("EfgModel '{}': node_spacing must be > 0", problem_.name));
  if (!(problem_.penalty_factor > 0.0))
    throw std::invalid_argument(fmt::format("EfgModel '{}': penalty_factor must be > 0", problem_.name));
  if (problem_.step_times.empty())
    throw std::invalid_argument(fmt::format("EfgModel '{}': no time steps", problem_.name));
  double previous = 0.0;
  for (double t : problem_.step_times) {
    if (!(t >= previous) || !std::isfinite(t))
      throw std::invalid_argument(fmt::format("EfgModel '{}': step times must be finite and non-decreasing from 0",
                                              problem_.name));
    previous = t;
  }
  alpha_ = problem_.alpha();  // eq. 23: alpha = penalty_factor * K1 / node_spacing [Pa/m]
}

EfgModel::~EfgModel() = default;

void EfgModel::install_cut(const core::RuledSurface* cut) {
  cut_weights_.reset();
  mls_->set_weight_modifier(nullptr);
  if (!cut) return;
  cut_weights_ = std::make_unique<CutWeights>(*cut, problem_.mesh.vertices, radii_->radii(), problem_.cut_treatment,
                                               problem_.front_transition);
  const CutWeights* weights = cut_weights_.get();
  mls_->set_weight_modifier([weights](int node, const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad) {
    return (*weights)(node, x, side, grad);
  });
}

void EfgModel::build_quadrature(QuadraturePoints* volume, QuadraturePoints* surface) const {
  const core::TetMesh& mesh = problem_.mesh;
  const core::RuledSurface* cut = problem_.cut ? &*problem_.cut : nullptr;
  *volume = volume_quadrature(mesh, problem_.quadrature_order, cut);
  *surface = boundary_quadrature(mesh, problem_.quadrature_order, cut);
  if (cut) surface->append(lip_quadrature(mesh, problem_.quadrature_order, *cut));
}

void EfgModel::setup_system() {
  auto t0 = std::chrono::steady_clock::now();
  const core::TetMesh& mesh = problem_.mesh;
  search_ = std::make_unique<NodeSearch>(mesh.vertices);
  radii_ = std::make_unique<SupportRadii>(mesh.vertices, *search_, problem_.support);
  mls_ = std::make_unique<MlsShapeFunctions>(mesh.vertices, *radii_, *search_);
  install_cut(problem_.cut ? &*problem_.cut : nullptr);
  QuadraturePoints vq, sq;
  build_quadrature(&vq, &sq);
  timings_.setup_seconds = seconds_since(t0);

  // Shape functions and gradients are tabulated once: the cloud does not move (eq. 17 small strain).
  t0 = std::chrono::steady_clock::now();
  const double spare = problem_.cut ? kSpareTableFraction : 0.0;
  volume_ = tabulate_shape_functions(*mls_, std::move(vq), true, spare);
  surface_ = tabulate_shape_functions(*mls_, std::move(sq), false, spare);
  timings_.shape_function_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  const int nq = volume_.size();
  states_.assign(nq, core::KelvinState{});
  const int n = mesh.num_vertices();
  u_ = Eigen::VectorXd::Zero(3 * n);
  previous_start_.reset();
  mixing_.reset();
  volume_incidence_ = NodeIncidence(volume_, n);
  surface_incidence_ = NodeIncidence(surface_, n);
  build_couplings(true);  // includes the solver's choice: an AMD ordering of the node pairs, part of the set-up cost
  timings_.setup_seconds += seconds_since(t0);
  set_up_ = true;
}

void EfgModel::build_couplings(bool new_pattern) {
  const core::TetMesh& mesh = problem_.mesh;
  const int n = mesh.num_vertices();
  for (int i = 0; i < n; ++i)
    if (volume_incidence_.offsets[i + 1] == volume_incidence_.offsets[i])
      throw std::runtime_error(fmt::format(
          "EfgModel '{}': node {} at ({:.6g}, {:.6g}, {:.6g}) mm covers no integration point (support radius "
          "{:.6g} mm); refine the background cells or raise support_factor",
          problem_.name, i, 1e3 * mesh.vertices(i, 0), 1e3 * mesh.vertices(i, 1), 1e3 * mesh.vertices(i, 2),
          1e3 * radii_->radius(i)));
  matrix_current_ = false;
  if (!new_pattern) {
    linear_solver_->forget_factors();  // the same method; the body changed, so the next solve factorises again
  } else {
    sparsity_ = std::make_unique<NodalSparsity>(
        n, std::vector<const ShapeTable*>{&volume_, &surface_},
        std::vector<const NodeIncidence*>{&volume_incidence_, &surface_incidence_});
    // A cut body keeps spare room in the matrix arrays for the node pairs a local update adds (advance_cut).
    // Swapped in: Eigen 3.4's SparseMatrix has no move assignment, and operator= would copy the arrays without
    // the spare room.
    SparseMatrix fresh = sparsity_->make_matrix(problem_.cut ? kSpareMatrixFraction : 0.0);
    matrix_.swap(fresh);
    // A new pattern (set-up, or a cut that advanced into new node pairs): choose and analyse the solver for it
    // again. The automatic choice runs an AMD ordering of the node pairs: part of the set-up cost.
    const auto t_choice = std::chrono::steady_clock::now();
    linear_solver_ = std::make_unique<EfgLinearSolver>(options_, *sparsity_, mesh.vertices, problem_.name);
    timings_.setup_seconds += seconds_since(t_choice);
    stats_.linear_solver = linear_solver_->description();
    stats_.linear_solver_kind = linear_solver_->kind();
    stats_.direct_peak_memory_estimate = linear_solver_->direct_peak_memory_estimate();
    stats_.direct_flops_estimate = linear_solver_->direct_flops_estimate();
    stats_.available_memory = linear_solver_->available_memory_bytes();
  }
  boundary_ = make_boundary_terms(problem_, surface_, alpha_);

  // Linear variationally consistent integration: xi_i = (oint phi_i n - int grad phi_i) / int_{supp i} 1, both
  // integrals by the same quadrature the assembly uses, so that the corrected test gradients satisfy the
  // discrete divergence theorem exactly (linear patch test to round-off, eq. 21 with eq. 24's traction term). The
  // boundary integral runs over the outer faces and over both lips of a cut: they bound the body too.
  // A local update of the cut (advance_cut) has already taken the rows it dropped out of these sums and added the
  // rows it evaluated (add_divergence_terms), a few per cent of them, instead of summing every row again.
  if (new_pattern) {
    defect_ = Eigen::Matrix3Xd::Zero(3, n);
    support_volume_ = Eigen::VectorXd::Zero(n);
    for (int q = 0; q < volume_.size(); ++q)
      for (int s = volume_.begin(q); s < volume_.end(q); ++s) {
        defect_.col(volume_.nodes[s]) -= volume_.weights[q] * volume_.dphi.col(s);
        support_volume_[volume_.nodes[s]] += volume_.weights[q];
      }
    for (int q = 0; q < surface_.size(); ++q)
      for (int s = surface_.begin(q); s < surface_.end(q); ++s)
        defect_.col(surface_.nodes[s]) += surface_.weights[q] * surface_.phi[s] * surface_.normals.col(q);
  }
  divergence_defect_ = defect_.colwise().norm().maxCoeff();
  vci_correction_ = Eigen::Matrix3Xd::Zero(3, n);
  if (problem_.variationally_consistent)
    for (int i = 0; i < n; ++i) vci_correction_.col(i) = defect_.col(i) / support_volume_[i];
  // Per-point arrays with room for the points a cut's local update adds (a cell split differently), so that an
  // update neither reallocates nor copies them.
  const int nq = volume_.size();
  const std::size_t room = problem_.cut ? static_cast<std::size_t>(nq * (1.0 + kSparePointFraction)) : nq;
  if (tangent_.capacity() < static_cast<std::size_t>(nq)) {
    std::vector<core::Matrix6>().swap(tangent_);  // scratch: its values need not be copied
    tangent_.reserve(room);
  }
  tangent_.resize(nq);  // scratch of the assembly, which sets it first (update_material): not cleared
  for (auto* v : {&strain_, &stress_}) {
    if (v->capacity() < static_cast<std::size_t>(nq)) {
      std::vector<core::Vector6>().swap(*v);
      v->reserve(room);
    }
    v->assign(nq, core::Vector6::Zero());
  }
  residual_ = Eigen::VectorXd::Zero(3 * n);
  external_ = Eigen::VectorXd::Zero(3 * n);

  stats_.num_nodes = n;
  stats_.num_cells = mesh.num_tets();
  stats_.num_volume_points = volume_.size();
  stats_.num_boundary_points = surface_.size();
  stats_.num_lip_points = 0;
  for (int q = 0; q < surface_.size(); ++q) stats_.num_lip_points += surface_.on_lip(q);
  stats_.num_cut_modified_nodes = cut_weights_ ? cut_weights_->num_modified() : 0;
  stats_.mean_nodes_per_point = nq > 0 ? static_cast<double>(volume_.num_entries()) / nq : 0.0;
  stats_.matrix_nonzeros = 9 * sparsity_->num_block_entries();
  stats_.alpha = boundary_.largest_alpha;  // alpha_ for a clamp; an elastic support's largest k_s
  stats_.penalised_area = boundary_.penalised_area;
  stats_.loaded_area = boundary_.loaded_area;
}

namespace {

/// The points of a table grouped by (cell, side), each group in increasing point order: a counting sort instead of
/// a hash map of vectors (one allocation per cell), which cost more than the rest of match_points on the lung.
struct PointsByCellAndSide {
  std::vector<int> offsets;  // per key (4 cell + side + 1), into `points`
  std::vector<int> points;
  static long long key(int cell, int side) { return 4LL * cell + (side + 1); }
  explicit PointsByCellAndSide(const ShapeTable& table) {
    long long keys = 0;
    for (int q = 0; q < table.size(); ++q) keys = std::max(keys, key(table.cells[q], table.sides[q]) + 1);
    offsets.assign(static_cast<std::size_t>(keys) + 1, 0);
    for (int q = 0; q < table.size(); ++q) ++offsets[key(table.cells[q], table.sides[q]) + 1];
    for (std::size_t k = 1; k < offsets.size(); ++k) offsets[k] += offsets[k - 1];
    points.resize(table.size());
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (int q = 0; q < table.size(); ++q) points[fill[key(table.cells[q], table.sides[q])]++] = q;
  }
  /// [first, last) into `points` of the group of (cell, side); empty when there is none.
  std::pair<int, int> group(int cell, int side) const {
    const long long k = key(cell, side);
    if (k < 0 || k + 1 >= static_cast<long long>(offsets.size())) return {0, 0};
    return {offsets[k], offsets[k + 1]};
  }
};

/// For each point of `now`, the row of `before` at the same place (same cell, same side, bitwise the same
/// coordinates), or -1. Of several such rows, the first.
template <class Points>  // QuadraturePoints or ShapeTable
std::vector<int> match_points(const ShapeTable& before, const Points& now) {
  const PointsByCellAndSide groups(before);
  std::vector<int> match(now.size(), -1);
  parallel_for(now.size(), 4096, [&](int q) {
    const auto [first, last] = groups.group(now.cells[q], now.sides[q]);
    for (int k = first; k < last; ++k)
      if (before.points.row(groups.points[k]) == now.points.row(q)) {
        match[q] = groups.points[k];
        break;
      }
  });
  return match;
}

/// History (eqs. 15-16) carried onto the volume points `now`, `same` their matches in `before` (match_points): a
/// point that is still there keeps its state; a new point (a cell split differently) takes the state of the nearest
/// old point of the same cell (the first of equally near ones).
template <class Points>  // QuadraturePoints or ShapeTable
std::vector<core::KelvinState> carried_history(const ShapeTable& before, const std::vector<core::KelvinState>& states,
                                               const Points& now, const std::vector<int>& same) {
  std::vector<core::KelvinState> carried(now.size());
  // The old points of the cells that have new points, by cell in increasing point order (a flag per cell, not a
  // hash map: the lookups run over every old point).
  int cells = 0;
  for (int q = 0; q < now.size(); ++q) cells = std::max(cells, now.cells[q] + 1);
  std::vector<char> has_new_points(cells, 0);
  for (int q = 0; q < now.size(); ++q)
    if (same[q] < 0) has_new_points[now.cells[q]] = 1;
  std::unordered_map<int, std::vector<int>> old_points_of_cell;
  for (int q = 0; q < before.size(); ++q) {
    const int c = before.cells[q];
    if (c < cells && has_new_points[c]) old_points_of_cell[c].push_back(q);
  }
  parallel_for(now.size(), 4096, [&](int q) {
    if (same[q] >= 0) carried[q] = states[same[q]];
  });
  for (int q = 0; q < now.size(); ++q) {
    if (same[q] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    for (int old : old_points_of_cell[now.cells[q]]) {
      const double d = (before.points.row(old) - now.points.row(q)).squaredNorm();
      if (d < best) {
        best = d;
        carried[q] = states[old];
      }
    }
  }
  return carried;
}

/// Adds sign times the terms of the given rows to the sums of the VCI correction (EfgModel::build_couplings):
/// defect_i = sum_surface w phi_i n - sum_volume w grad phi_i, support_i = sum_volume w. `surface` is false for
/// rows of the volume table.
void add_divergence_terms(const ShapeTable& table, bool surface, const std::vector<int>& rows, double sign,
                          Eigen::Matrix3Xd* defect, Eigen::VectorXd* support) {
  for (int q : rows)
    for (int s = table.begin(q); s < table.end(q); ++s) {
      const int i = table.nodes[s];
      if (surface) {
        defect->col(i) += sign * (table.weights[q] * table.phi[s] * table.normals.col(q));
      } else {
        defect->col(i) -= sign * (table.weights[q] * table.dphi.col(s));
        (*support)[i] += sign * table.weights[q];
      }
    }
}

/// The rows of `before` that no point of the update reuses (reuse as given to update_shape_functions).
std::vector<int> dropped_rows(const ShapeTable& before, const std::vector<int>& reuse) {
  std::vector<char> kept(before.size(), 0);
  for (int r : reuse)
    if (r >= 0) kept[r] = 1;
  std::vector<int> rows;
  for (int q = 0; q < before.size(); ++q)
    if (!kept[q]) rows.push_back(q);
  return rows;
}

/// The old node lists of the points an update evaluates again (reuse[q] < 0) that are still there (same[q] >= 0, their
/// row of `table` before the update), copied before the update overwrites the table: a re-evaluated point whose
/// nodes are all among its old ones couples no node pair that the pattern lacks.
struct OldNodeLists {
  std::vector<int> offsets{0}, nodes;
  std::vector<int> index;  // per point of the update: its list, or -1
  OldNodeLists(const ShapeTable& table, const std::vector<int>& reuse, const std::vector<int>& same)
      : index(reuse.size(), -1) {
    for (std::size_t q = 0; q < reuse.size(); ++q) {
      if (reuse[q] >= 0 || same[q] < 0) continue;
      index[q] = static_cast<int>(offsets.size()) - 1;
      nodes.insert(nodes.end(), table.nodes.begin() + table.begin(same[q]), table.nodes.begin() + table.end(same[q]));
      offsets.push_back(static_cast<int>(nodes.size()));
    }
  }
  /// The re-evaluated points of the updated `table` that may couple a node pair the pattern lacks: new points, and
  /// those with a node they did not have (the rows' nodes are ascending).
  std::vector<int> rows_with_new_nodes(const ShapeTable& table, const std::vector<int>& reuse) const {
    std::vector<int> rows;
    for (int q = 0; q < table.size(); ++q) {
      if (reuse[q] >= 0) continue;
      const int k = index[q];
      if (k < 0 || !std::includes(nodes.begin() + offsets[k], nodes.begin() + offsets[k + 1],
                                  table.nodes.begin() + table.begin(q), table.nodes.begin() + table.end(q)))
        rows.push_back(q);
    }
    return rows;
  }
};

}  // namespace

/// What decides, under the enrichment, whether a point's weights change between two cuts. h_i(X) =
/// (1 + sigma_i Phi(X)) / 2 for a node the cut modifies and 1 otherwise (eq. 32): node i enters only through
/// whether it is modified and its side sigma_i, and the point only through Phi. So a point changes when a node
/// whose (modified, sigma_i) changed covers it, or when Phi (or its gradient) changed and a node modified by either
/// cut covers it. Either way a node modified by either cut covers it, and those nodes are few next to the cloud:
/// one search over them alone answers both, and Phi is compared only at the points they cover.
class NodesWithNewEnrichment {
 public:
  NodesWithNewEnrichment(const CutWeights& before, const CutWeights& after, const core::PointMatrix& nodes,
                         const SupportRadii& radii) {
    std::vector<int> modified;
    for (int i = 0; i < nodes.rows(); ++i)
      if (before.modifies(i) || after.modifies(i)) {
        modified.push_back(i);
        changed_.push_back(before.modifies(i) != after.modifies(i) ||
                           (after.modifies(i) && before.node_side(i) != after.node_side(i)));
      }
    positions_.resize(static_cast<Eigen::Index>(modified.size()), 3);
    radii_.resize(static_cast<Eigen::Index>(modified.size()));
    for (std::size_t k = 0; k < modified.size(); ++k) {
      positions_.row(k) = nodes.row(modified[k]);
      radii_[k] = radii.radius(modified[k]);
    }
    if (modified.empty()) return;
    max_radius_ = radii_.maxCoeff();
    search_ = std::make_unique<NodeSearch>(positions_);
  }
  /// True when a node modified by either cut covers x; `hits` then lists them (as rows of this set).
  bool modified_node_covers(const Eigen::Vector3d& x, std::vector<NodeHit>* hits) const {
    if (!search_) return false;
    search_->covering(x, radii_, max_radius_, hits);
    return !hits->empty();
  }
  /// True when one of `hits` (of modified_node_covers) is a node whose enrichment data changed.
  bool changed_among(const std::vector<NodeHit>& hits) const {
    for (const NodeHit& hit : hits)
      if (changed_[hit.node]) return true;
    return false;
  }

 private:
  core::PointMatrix positions_;  // the modified nodes; the KD-tree references it
  Eigen::VectorXd radii_;
  std::vector<char> changed_;
  double max_radius_ = 0.0;
  std::unique_ptr<NodeSearch> search_;
};

bool EfgModel::weights_changed(const CutWeights* before, const Eigen::Vector3d& x, int side, bool gradients,
                               std::vector<NodeHit>* hits, const NodesWithNewEnrichment* enrichment) const {
  constexpr double kTolerance = 1e-13;  // round-off of h and of rho * grad h
  if (enrichment) {
    // h_i = (1 + sigma_i Phi) / 2: the weights of unchanged nodes move with Phi alone (and their gradients with
    // grad Phi / 2, compared at the largest radius, as below). Nothing changes where no modified node reaches.
    if (!enrichment->modified_node_covers(x, hits)) return false;
    if (enrichment->changed_among(*hits)) return true;
    const CutWeights& after = *cut_weights_;
    Eigen::Vector3d g0, g1;
    const double phi0 = before->enrichment_function(x, side, gradients ? &g0 : nullptr);
    const double phi1 = after.enrichment_function(x, side, gradients ? &g1 : nullptr);
    return 0.5 * std::abs(phi1 - phi0) > kTolerance ||
           (gradients && 0.5 * radii_->max_radius() * (g1 - g0).norm() > kTolerance);
  }
  search_->covering(x, radii_->radii(), radii_->max_radius(), hits);
  const CutWeights* after = cut_weights_.get();
  Eigen::Vector3d g0 = Eigen::Vector3d::Zero(), g1 = Eigen::Vector3d::Zero();
  for (const NodeHit& hit : *hits) {
    const int i = hit.node;
    if (!(before && before->modifies(i)) && !(after && after->modifies(i))) continue;
    const double h0 = before ? (*before)(i, x, side, gradients ? &g0 : nullptr) : 1.0;
    const double h1 = after ? (*after)(i, x, side, gradients ? &g1 : nullptr) : 1.0;
    if (std::abs(h1 - h0) > kTolerance) return true;
    if (gradients && radii_->radius(i) * (g1 - g0).norm() > kTolerance) return true;
  }
  return false;
}

CutUpdate EfgModel::advance_cut(const core::RuledSurface& cut) {
  if (!set_up_) throw std::logic_error("EfgModel::advance_cut before setup_system");
  const auto t0 = std::chrono::steady_clock::now();
  CutUpdate report;
  const std::unique_ptr<CutWeights> before = std::move(cut_weights_);
  const std::optional<core::RuledSurface> previous_cut = problem_.cut;
  problem_.cut = cut;
  install_cut(&cut);
  QuadraturePoints vq, sq;
  build_quadrature(&vq, &sq);

  // Reuse the shape functions of every point that is still there and whose covering nodes keep their weights
  // (paper §4: only the shape functions near the new part of the cut are computed again). A node's weight can
  // change only if its support meets the cut (old or new), so points farther than 2 rho_max from both cuts are
  // reused without looking.
  const double reach = 2.0 * radii_->max_radius();
  // A cheap bound first: the distance to a cut is at least the distance of the projections along its depth
  // direction (the cut is open upward), so a point whose projection is farther than `reach` from the box around
  // both traces is far from both cuts.
  const Eigen::Vector3d depth_direction = cut.direction();
  Eigen::AlignedBox3d traces;
  for (const core::RuledSurface* c : {&cut, previous_cut ? &*previous_cut : nullptr})
    if (c)
      for (const Eigen::Vector3d& p : c->top()) traces.extend(p - p.dot(c->direction()) * c->direction());
  const bool same_direction = !previous_cut || previous_cut->direction() == depth_direction;
  auto may_be_near = [&](const Eigen::Vector3d& x) {
    return !same_direction || traces.exteriorDistance(x - x.dot(depth_direction) * depth_direction) < reach;
  };
  std::unique_ptr<NodesWithNewEnrichment> enrichment;
  if (before && before->treatment() == CutTreatment::enrichment && cut_weights_->treatment() == CutTreatment::enrichment &&
      before->front_transition() == cut_weights_->front_transition())
    enrichment = std::make_unique<NodesWithNewEnrichment>(*before, *cut_weights_, problem_.mesh.vertices, *radii_);
  auto reuse_of = [&](const std::vector<int>& same, const QuadraturePoints& points, bool gradients, int* recomputed) {
    std::vector<int> reuse = same;
    std::vector<char> changed(points.size(), 0);
    parallel_for(points.size(), 256, [&](int q) {
      thread_local std::vector<NodeHit> hits;
      if (reuse[q] < 0) return;
      const Eigen::Vector3d x = points.points.row(q).transpose();
      // Under the enrichment the search over the modified nodes is itself the test of nearness (a node modified
      // by a cut is nearer to it than its radius, so the points it covers are within 2 rho_max): the distances to
      // the cuts (two frames per point) are not needed.
      const bool near = may_be_near(x) && (enrichment || cut.frame(x).distance < reach ||
                                           (previous_cut && previous_cut->frame(x).distance < reach));
      if (near && weights_changed(before.get(), x, points.sides[q], gradients, &hits, enrichment.get()))
        changed[q] = 1;
    });
    for (int q = 0; q < points.size(); ++q) {
      if (changed[q]) reuse[q] = -1;
      *recomputed += reuse[q] < 0;
    }
    return reuse;
  };
  const std::vector<int> volume_same = match_points(volume_, vq);
  const std::vector<int> volume_reuse = reuse_of(volume_same, vq, true, &report.volume_points_recomputed);
  const std::vector<int> surface_same = match_points(surface_, sq);
  const std::vector<int> surface_reuse = reuse_of(surface_same, sq, false, &report.boundary_points_recomputed);
  report.volume_points = vq.size();
  report.boundary_points = sq.size();

  // History (eqs. 15-16): a point that is still there keeps its state; a new point (a cell split differently)
  // takes the state of the nearest old point of the same cell.
  std::vector<core::KelvinState> states = carried_history(volume_, states_, vq, volume_same);

  // Read from the tables before the update changes them: the terms of the rows it drops leave the VCI sums, and the
  // old node lists of the points it evaluates again tell which of them can couple a new node pair.
  const int n = problem_.mesh.num_vertices();
  const std::vector<int> volume_dropped = dropped_rows(volume_, volume_reuse);
  const std::vector<int> surface_dropped = dropped_rows(surface_, surface_reuse);
  add_divergence_terms(volume_, false, volume_dropped, -1.0, &defect_, &support_volume_);
  add_divergence_terms(surface_, true, surface_dropped, -1.0, &defect_, &support_volume_);
  // Per node, the incidence entries of the dropped rows: the merged incidence's counts without a pass over all.
  auto entries_per_node = [n](const ShapeTable& table, const std::vector<int>& rows) {
    std::vector<int> count(n, 0);
    for (int q : rows)
      for (int s = table.begin(q); s < table.end(q); ++s) ++count[table.nodes[s]];
    return count;
  };
  const std::vector<int> volume_dropped_entries = entries_per_node(volume_, volume_dropped);
  const std::vector<int> surface_dropped_entries = entries_per_node(surface_, surface_dropped);
  const OldNodeLists volume_old_nodes(volume_, volume_reuse, volume_same);
  const OldNodeLists surface_old_nodes(surface_, surface_reuse, surface_same);

  report.quadrature_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const bool volume_packed = update_shape_functions(*mls_, std::move(vq), volume_reuse, kSpareTableFraction, &volume_).packed;
  const bool surface_packed = update_shape_functions(*mls_, std::move(sq), surface_reuse, kSpareTableFraction, &surface_).packed;
  report.tables_packed = volume_packed || surface_packed;
  report.shape_function_seconds = seconds_since(t1);
  states_ = std::move(states);

  // A reused row keeps its nodes, whose pairs the pattern holds; only the recomputed rows can bring a new pair.
  const auto t2 = std::chrono::steady_clock::now();
  // The incidence follows the tables: merged from the one before when the kept rows stayed in their slots.
  // The merged incidence is written into the arrays of the one before last (kept for this), so that the update does
  // not allocate (and fault in) 70 MB afresh on the lung.
  auto follow = [n](const ShapeTable& table, bool packed, const std::vector<int>& reuse,
                    const std::vector<int>& dropped_entries, NodeIncidence* incidence, NodeIncidence* spare) {
    if (packed) {
      *incidence = NodeIncidence(table, n);
      return;
    }
    merge_incidence(*incidence, table, reuse, spare, &dropped_entries);
    std::swap(*incidence, *spare);
  };
  follow(volume_, volume_packed, volume_reuse, volume_dropped_entries, &volume_incidence_, &spare_volume_incidence_);
  follow(surface_, surface_packed, surface_reuse, surface_dropped_entries, &surface_incidence_,
         &spare_surface_incidence_);
  auto evaluated_rows = [](const std::vector<int>& reuse) {
    std::vector<int> rows;
    for (int q = 0; q < static_cast<int>(reuse.size()); ++q)
      if (reuse[q] < 0) rows.push_back(q);
    return rows;
  };
  add_divergence_terms(volume_, false, evaluated_rows(volume_reuse), 1.0, &defect_, &support_volume_);
  add_divergence_terms(surface_, true, evaluated_rows(surface_reuse), 1.0, &defect_, &support_volume_);
  int first_row = n;  // the first node whose row of the pattern gained a pair
  report.pairs_added = sparsity_->add_pairs(volume_, volume_old_nodes.rows_with_new_nodes(volume_, volume_reuse), &first_row) +
                       sparsity_->add_pairs(surface_, surface_old_nodes.rows_with_new_nodes(surface_, surface_reuse), &first_row);
  if (report.pairs_added > 0) {
    // In the spare room kept at set-up, rewriting only the rows from the first that changed (the values are
    // assembled before the next solve).
    sparsity_->refill_matrix(&matrix_, first_row);
    // A solver's symbolic analysis (UMFPACK's ordering) belongs to the old pattern: start a solver of the method
    // chosen at set-up afresh. Without new pairs the kept solver reuses its analysis.
    EfgOptions chosen = options_;
    chosen.linear_solver = linear_solver_->kind();
    linear_solver_ = std::make_unique<EfgLinearSolver>(chosen, *sparsity_, problem_.mesh.vertices, problem_.name);
  }
  build_couplings(false);
  report.coupling_seconds = seconds_since(t2);
  report.seconds = seconds_since(t0);
  report.modified_nodes = cut_weights_->num_modified();
  // The last step's increment and the secant pairs were in the old cut's shape functions.
  previous_start_.reset();
  mixing_.reset();
  return report;
}

void EfgModel::continue_from(const EfgModel& earlier) {
  if (!set_up_ || !earlier.set_up_) throw std::logic_error("EfgModel::continue_from before setup_system");
  auto same = [](const auto& a, const auto& b) { return a.rows() == b.rows() && a.cols() == b.cols() && a == b; };
  if (!same(earlier.problem_.mesh.vertices, problem_.mesh.vertices) || !same(earlier.problem_.mesh.tets, problem_.mesh.tets))
    throw std::invalid_argument(fmt::format("EfgModel '{}': continue_from needs the same node cloud and cells",
                                            problem_.name));
  states_ = carried_history(earlier.volume_, earlier.states_, volume_, match_points(earlier.volume_, volume_));
  u_ = earlier.u_;
  previous_start_.reset();
  mixing_.reset();
  matrix_current_ = false;
}

void EfgModel::update_material(double dt, bool with_tangent) {
  // eq. 17: strain from the current parameters; eq. 13 through the shared law (one state per point). The
  // tangent only when a matrix is assembled: most of the law's work, and unread by a residual-only iteration.
  const ShapeTable& t = volume_;
  const bool check_margin = problem_.material.k != 0.0;  // the margin is 1 everywhere when k = 0
  if (check_margin) margins_.resize(t.size());
  parallel_for(t.size(), 512, [&](int q) {
    const core::Vector6 e = strain_at(t, q, u_);
    strain_[q] = e;
    if (!e.allFinite())
      throw std::runtime_error(fmt::format("EfgModel '{}': non-finite strain at volume point {}", problem_.name, q));
    if (check_margin) margins_[q] = law_.admissibility_margin(e);
    if (with_tangent) {
      const core::KelvinResponse r = law_.update(states_[q], e, dt);
      stress_[q] = r.stress;
      tangent_[q] = r.tangent;
    } else {
      stress_[q] = law_.updated_stress(states_[q], e, dt);
    }
  });
  // The law's admissible range (docs/MATERIAL.md §1.5), at every point of every iterate; newton_step() decides
  // what a point past it means (core/step_cutback.hpp).
  weakest_point_ = -1;
  if (!check_margin || margins_.empty()) return;
  weakest_point_ = static_cast<int>(std::min_element(margins_.begin(), margins_.end()) - margins_.begin());
}

std::shared_ptr<const core::InadmissibleStrain> EfgModel::inadmissible_iterate() const {
  if (weakest_point_ < 0 || law_.admits(margins_[weakest_point_])) return nullptr;
  return std::make_shared<const core::InadmissibleStrain>(
      fmt::format("meshless (EFG) model '{}'", problem_.name), current_time_,
      volume_.points.row(weakest_point_).transpose(), strain_[weakest_point_], law_);
}

void EfgModel::add_internal_forces() {
  // f_i = sum_q w_q B_i(X_q)^T sigma_q (eq. 21).
  weighted_stress_.resize(stress_.size());
  parallel_for(volume_.size(), 4096, [&](int q) { weighted_stress_[q] = volume_.weights[q] * stress_[q]; });
  add_test_gradient_sums(weighted_stress_, &residual_);
}

void EfgModel::add_test_gradient_sums(const std::vector<core::Vector6>& weighted, Eigen::VectorXd* out) {
  // out_i = sum_q B_i(X_q)^T weighted_q, the test gradient with the VCI correction of node i. Point by point, so
  // that the table (tens of bytes per point-node entry, hundreds of MB on the lung) is read once in its order; node
  // by node through the incidence each entry was a cache miss (lung_small's residual: 0.207 s that way, 0.034 s this
  // way; bench_efg's BM_EfgAssemblyLung/0). The points are split into a fixed number of consecutive blocks, each
  // summed into its own vector, and the blocks are added in their order: the sum does not depend on the number of
  // threads or on their timing.
  const ShapeTable& vt = volume_;
  const int n = problem_.mesh.num_vertices();
  const int points = vt.size();
  const int blocks = std::clamp(points / 4096, 1, 32);
  if (force_blocks_.rows() != 3 * n || force_blocks_.cols() != blocks) force_blocks_.resize(3 * n, blocks);
  parallel_for(blocks, 1, [&](int b) {
    double* f = force_blocks_.col(b).data();
    std::fill(f, f + 3 * n, 0.0);
    const int q_end = static_cast<int>(static_cast<long long>(points) * (b + 1) / blocks);
    for (int q = static_cast<int>(static_cast<long long>(points) * b / blocks); q < q_end; ++q) {
      const core::Vector6& ws = weighted[q];
      for (int s = vt.begin(q); s < vt.end(q); ++s) {
        const int j = vt.nodes[s];
        const Eigen::Vector3d g = vt.dphi.col(s) + vci_correction_.col(j);
        // B_j^T ws with the zero pattern of eq. 22 spelt out (Voigt order xx, yy, zz, xy, yz, xz).
        f[3 * j] += g.x() * ws[0] + g.y() * ws[3] + g.z() * ws[5];
        f[3 * j + 1] += g.y() * ws[1] + g.x() * ws[3] + g.z() * ws[4];
        f[3 * j + 2] += g.z() * ws[2] + g.y() * ws[4] + g.x() * ws[5];
      }
    }
  });
  *out = force_blocks_.col(0);
  for (int b = 1; b < blocks; ++b) *out += force_blocks_.col(b);
}

void EfgModel::apply_tangent(const Eigen::VectorXd& v, Eigen::VectorXd* out) {
  if (!set_up_) throw std::logic_error("EfgModel::apply_tangent before setup_system");
  // (K_n + K^alpha_n) v of eq. 20 without the matrix: sum_q w_q B_i^T E_k,q eps_q(v) (eq. 21), then the penalty's
  // sum_q alpha phi_i u_v(X_q) (eq. 23). The same sums as the assembled tangent's, in another order.
  weighted_stress_.resize(volume_.size());
  parallel_for(volume_.size(), 512, [&](int q) {
    weighted_stress_[q] = volume_.weights[q] * (tangent_[q] * strain_at(volume_, q, v));
  });
  add_test_gradient_sums(weighted_stress_, out);
  const ShapeTable& sv = surface_;
  const std::vector<Eigen::Vector3d> v_surface = penalised_surface_values(v);
  for (int q = 0; q < sv.size(); ++q) {
    const double c = boundary_.penalty_weight[q];
    if (c == 0.0) continue;
    for (int s = sv.begin(q); s < sv.end(q); ++s) out->segment<3>(3 * sv.nodes[s]) += (c * sv.phi[s]) * v_surface[q];
  }
}

std::vector<Eigen::Vector3d> EfgModel::penalised_surface_values(const Eigen::VectorXd& u) const {
  const ShapeTable& sv = surface_;
  std::vector<Eigen::Vector3d> values(sv.size(), Eigen::Vector3d::Zero());
  for (int q = 0; q < sv.size(); ++q) {
    if (boundary_.penalty_weight[q] == 0.0) continue;
    for (int s = sv.begin(q); s < sv.end(q); ++s) values[q] += sv.phi[s] * u.segment<3>(3 * sv.nodes[s]);
  }
  return values;
}

void EfgModel::assemble_system(bool with_matrix) {
  if (!set_up_) throw std::logic_error("EfgModel::assemble_system before setup_system");
  update_material(current_dt_, with_matrix);

  // u-bar mismatch of the penalty term needs u(X_q) = sum phi_j U_j at the penalised boundary points.
  const ShapeTable& sv = surface_;
  const std::vector<Eigen::Vector3d> u_surface = penalised_surface_values(u_);

  // The internal forces point by point (eq. 21's int B_i^T sigma): they read the shape-function table in its order.
  add_internal_forces();

  const int n = problem_.mesh.num_vertices();
  double* values = matrix_.valuePtr();
  const NodalSparsity& sp = *sparsity_;
  const ShapeTable& vt = volume_;
  // The rows the linear solver reads: all, or this process's share of a distributed solve. The residual is
  // assembled whole on every process (each runs the same Newton iterations).
  const auto [first_row_node, end_row_node] = linear_solver_->nodes_read(n);
  // The tangent row by row (the equations of node i): each thread owns whole rows, so no locks or atomics are
  // needed. With them the penalty term and the external load, which are few and per node.
  parallel_for(n, 16, [&](int i) {
    const bool with_row = with_matrix && i >= first_row_node && i < end_row_node;
    thread_local std::vector<int> position;
    double* row[3] = {nullptr, nullptr, nullptr};
    if (with_row) {
      if (static_cast<int>(position.size()) != n) position.assign(n, -1);
      for (int k = sp.row_begin(i); k < sp.row_end(i); ++k) position[sp.column(k)] = k - sp.row_begin(i);
      const int len = sp.row_length(i);
      for (int a = 0; a < 3; ++a) {
        row[a] = values + sp.value_index(i, a, 0, 0);
        std::fill(row[a], row[a] + 3 * len, 0.0);
      }
      // eq. 24's int B_i^T E_k B_j.
      for (int e = volume_incidence_.offsets[i]; e < volume_incidence_.offsets[i + 1]; ++e) {
        const int q = volume_incidence_.points[e];
        const Eigen::Vector3d g = vt.dphi.col(volume_incidence_.slots[e]) + vci_correction_.col(i);
        const Eigen::Matrix<double, 3, 6> gd = vt.weights[q] * (b_transpose(g) * tangent_[q]);
        // (B_i^T E_k) B_j is linear in h = grad phi_j: the 3x3 block is m h, row 3a + c of m holding B_j's zero
        // pattern (eq. 22). One small fixed-size product per node j, which Eigen vectorises: lung_small's tangent in
        // 1.27-1.36 s against 1.53-1.58 s with the 27 multiply-adds written out (BM_EfgAssemblyLung/1).
        Eigen::Matrix<double, 9, 3> m;
        for (int a = 0; a < 3; ++a) {
          m.row(3 * a) << gd(a, 0), gd(a, 3), gd(a, 5);
          m.row(3 * a + 1) << gd(a, 3), gd(a, 1), gd(a, 4);
          m.row(3 * a + 2) << gd(a, 5), gd(a, 4), gd(a, 2);
        }
        for (int s = vt.begin(q); s < vt.end(q); ++s) {
          const int k = position[vt.nodes[s]];
          const Eigen::Matrix<double, 9, 1> block = m * vt.dphi.col(s);
          for (int a = 0; a < 3; ++a) {
            double* v = row[a] + 3 * k;
            v[0] += block[3 * a];
            v[1] += block[3 * a + 1];
            v[2] += block[3 * a + 2];
          }
        }
      }
    }
    Eigen::Vector3d f = residual_.segment<3>(3 * i);  // the internal force
    // eq. 23: K^alpha_ij = int alpha phi_i phi_j I3, and its residual alpha int phi_i u(X) (u-bar part is external).
    for (int e = surface_incidence_.offsets[i]; e < surface_incidence_.offsets[i + 1]; ++e) {
      const int q = surface_incidence_.points[e];
      const double c = boundary_.penalty_weight[q];
      if (c == 0.0) continue;
      const double ci = c * sv.phi[surface_incidence_.slots[e]];
      f += ci * u_surface[q];
      if (!with_row) continue;
      for (int s = sv.begin(q); s < sv.end(q); ++s) {
        const int k = position[sv.nodes[s]];
        const double v = ci * sv.phi[s];
        for (int a = 0; a < 3; ++a) row[a][3 * k + a] += v;
      }
    }
    residual_.segment<3>(3 * i) = f - external_.segment<3>(3 * i);
    if (with_row)
      for (int k = sp.row_begin(i); k < sp.row_end(i); ++k) position[sp.column(k)] = -1;
  });
  if (!residual_.allFinite())
    throw std::runtime_error(fmt::format("EfgModel '{}': the residual is not finite", problem_.name));
  if (with_matrix) {
    matrix_current_ = true;
    linear_solver_->invalidate();
  }
}

void EfgModel::solve(double tolerance) {
  if (!linear_solver_ || (!matrix_current_ && !tangent_by_points_ && !linear_solver_->prepared()))
    throw std::logic_error("EfgModel::solve without an assembled matrix");
  last_solve_prepared_ = false;
  const bool by_points = tangent_by_points_;
  tangent_by_points_ = false;
  if (!linear_solver_->prepared()) {
    // A newer tangent than the factors: GMRES preconditioned by them costs a few back-substitutions, a fresh
    // factorisation tens of seconds on the lung (docs/MESHLESS.md §2). factorised_dt_ stays that of the factors.
    std::optional<Eigen::VectorXd> du;
    if (by_points) {
      const EfgLinearSolver::LinearOperator tangent = [this](const Eigen::VectorXd& v, Eigen::VectorXd* out) {
        apply_tangent(v, out);
      };
      du = linear_solver_->solve_with_earlier_factors(tangent, -residual_, options_.earlier_factors_max_iterations,
                                                      tolerance);
    } else {
      du = linear_solver_->solve_with_earlier_factors(matrix_, -residual_, options_.earlier_factors_max_iterations,
                                                      tolerance);
    }
    if (du) {
      u_ += *du;
      last_linear_iterations_ = linear_solver_->last_iterations();
      return;
    }
    if (by_points) assemble_system(true);  // the factorisation needs this iterate's matrix
    linear_solver_->prepare(matrix_);
    last_solve_prepared_ = true;
    stats_.linear_solver = linear_solver_->description();  // a multigrid reports its levels once built
  }
  u_ += linear_solver_->solve(-residual_);  // eq. 14; solve() checks the update is finite
  last_linear_iterations_ = linear_solver_->last_iterations();
  factorised_dt_ = current_dt_;
}

StepRecord EfgModel::solve_step(int step) {
  if (!set_up_) throw std::logic_error("EfgModel::solve_step before setup_system");
  const std::vector<double>& times = problem_.step_times;
  if (step < 1 || step > static_cast<int>(times.size())) throw std::out_of_range("EfgModel::solve_step: bad step");
  StepRecord rec;
  rec.step = step;
  rec.time = times[step - 1];
  const double t_start = step >= 2 ? times[step - 2] : 0.0;
  rec.dt = rec.time - t_start;
  rec.load_scale = problem_.load_scale(rec.time);
  // One Newton solve over the whole step; halved sub-steps only when it fails.
  const core::CutBackRecord cut = core::advance_with_cutback(
      fmt::format("meshless (EFG) model '{}'", problem_.name), t_start, rec.time, problem_.min_step,
      [&](double t_from, double t_to) { return newton_step(t_from, t_to, &rec); });
  rec.substeps = cut.substeps;
  rec.cutbacks = cut.cutbacks;
  rec.failed_attempts = cut.failures;
  timings_.assembly_seconds += rec.assembly_seconds;
  timings_.solve_seconds += rec.solve_seconds;
  records_.push_back(rec);
  return rec;
}

double EfgModel::gmres_tolerance(double relative_residual, double target_over_residual) const {
  if (!(options_.gmres_forcing > 0.0)) return options_.iterative_tolerance;
  // Eisenstat-Walker: Newton contracts ||R|| to about forcing * ||R|| + O(||R||^2), so a linear residual below
  // forcing * (relative residual) keeps the convergence superlinear; and half of what is left to the tolerance
  // lets the last iteration finish. Any more is GMRES work that Newton's next residual would not see.
  const double wanted = std::max(options_.gmres_forcing * relative_residual, 0.5 * target_over_residual);
  return std::clamp(wanted, options_.iterative_tolerance, options_.gmres_forcing);
}

core::NewtonAttempt EfgModel::newton_step(double t_from, double t_to, StepRecord* rec) {
  const Eigen::VectorXd u_start = u_;  // the committed state: restored when an attempt fails
  const bool predicted = predict_start(t_from, t_to);
  const bool accelerated = predicted || options_.anderson_depth > 0;
  core::NewtonAttempt attempt = newton_iterations(t_from, t_to, u_start, accelerated, rec);
  if (!attempt.converged() && accelerated) {
    // The plain iteration from the committed state is the fallback: what the acceleration changes is the path,
    // never the equilibrium, so a failure it caused must not cost a halved step. The failed attempt is kept.
    attempt.failure = "with the predictor and Anderson mixing (EfgOptions): " + attempt.failure;
    rec->retried_plain.push_back(attempt);
    u_ = u_start;
    attempt = newton_iterations(t_from, t_to, u_start, false, rec);
  }
  if (!attempt.converged()) return attempt;
  // A converged state past the range is no equilibrium of the law: no step size helps, stop the run.
  if (auto outside = inadmissible_iterate()) {
    u_ = u_start;
    throw core::InadmissibleStrain(*outside);
  }
  attempt.inadmissible = nullptr;
  rec->residuals = attempt.residuals;
  if (weakest_point_ >= 0) {
    const double m = margins_[weakest_point_];
    rec->admissibility_margin = std::min(rec->admissibility_margin, m);
    smallest_margin_.update(m, t_to, volume_.points.row(weakest_point_).transpose(), strain_[weakest_point_]);
  }
  // Commit the history (eqs. 15-16) at the converged strain of every point.
  parallel_for(volume_.size(), 1024, [&](int q) { law_.update(states_[q], strain_[q], current_dt_, &states_[q]); });
  previous_start_ = PreviousStep{u_start, t_from, t_to};
  return attempt;
}

bool EfgModel::predict_start(double t_from, double t_to) {
  if (!options_.extrapolate_start || !previous_start_ || previous_start_->u.size() != u_.size()) return false;
  const PreviousStep& p = *previous_start_;
  const double dt_before = p.t_to - p.t_from, dt = t_to - t_from;
  if (!(dt_before > 0.0) || std::abs(p.t_to - t_from) > 1e-9 * dt_before) return false;  // not the step before
  if (!core::load_keeps_its_rate(problem_.load_scale, p.t_from, t_from, t_to)) return false;
  u_ += (dt / dt_before) * (u_ - p.u);  // U_{n+1} ~ U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1})
  matrix_current_ = false;
  return true;
}

core::NewtonAttempt EfgModel::newton_iterations(double t_from, double t_to, const Eigen::VectorXd& u_start,
                                                bool accelerated, StepRecord* rec) {
  core::NewtonAttempt attempt;
  attempt.t_start = t_from;
  attempt.t_end = t_to;
  current_time_ = t_to;
  current_dt_ = t_to - t_from;
  external_ = boundary_.penalty_load + problem_.load_scale(t_to) * boundary_.traction_load;
  double reference = external_.norm();

  // Newton with tangent reuse. A factorisation costs seconds (dense EFG rows), a back-substitution a
  // fraction of that, so the last factorised consistent tangent is kept while it still contracts the
  // residual (ratio <= options_.refactor_contraction) fast enough to reach the tolerance within the iteration
  // limit, and refreshed when it does not or when dt changed. With k = 0 the tangent depends on dt only
  // (eq. 13: E_k = factor(dt) C0) and is exact. On kept factors the updates are Anderson-mixed
  // (meshless/solvers/anderson_acceleration.hpp), which restarts whenever the factors change.
  // Exact factors of a tangent that cannot change: iterate on them without watching the rate.
  const bool constant_tangent = problem_.material.k == 0.0 && !(options_.direct_low_rank_tolerance > 0.0);
  const core::DivergenceTest diverging;
  AndersonAcceleration unmixed(0);
  AndersonAcceleration& mixing = accelerated ? mixing_ : unmixed;
  mixing.start_sequence();
  // The factors' dt, compared to round-off: step times are sums (0.6 - 0.4 is 0.2 + 1e-16), and a
  // last-bit difference must not cost a factorisation.
  auto factors_dt = [&] { return std::abs(factorised_dt_ - current_dt_) <= 1e-9 * std::abs(current_dt_); };
  double previous = std::numeric_limits<double>::infinity();
  Eigen::VectorXd u_before, plain_update;  // the last solve's iterate and its unmixed update
  bool last_mixed = false;
  for (int it = 0;; ++it) {
    const bool reuse = linear_solver_->prepared() && factors_dt();
    auto t0 = std::chrono::steady_clock::now();
    try {
      assemble_system(!reuse);
    } catch (const std::runtime_error& e) {
      attempt.failure = e.what();
      break;
    }
    // A transient iterate past the admissible range is remembered, not fatal: if Newton fails, the first such
    // iterate is reported (later iterates of a failing attempt drifted further off on the lung-tip case).
    if (!attempt.inadmissible) attempt.inadmissible = inadmissible_iterate();
    if (reuse) rec->reused_factorisation = true;
    rec->assembly_seconds += seconds_since(t0);
    const double r = residual_.norm();
    if (last_mixed && !(r <= previous)) {
      // The mix raised ||R||: its secants (on the cut lung, those carried over from the last step, beside the crack
      // front) no longer describe the tangent. Take the plain update from the same iterate instead and mix afresh
      // from there, rather than let the rise refresh the tangent. Costs this residual.
      u_ = u_before + plain_update;
      mixing.reset();
      last_mixed = false;
      ++rec->rejected_mixes;
      continue;
    }
    if (!(reference > 0.0)) reference = r > 0.0 ? r : 1.0;
    attempt.residuals.push_back(r / reference);
    attempt.failure = diverging(attempt.residuals);
    if (!attempt.converged()) break;
    const double target = options_.newton_tolerance * reference;
    const double last = previous;
    previous = r;
    if (r <= target) break;
    if (it >= options_.max_newton_iterations) {
      attempt.failure = "the iteration limit (max_newton_iterations) was reached";
      break;
    }
    // The kept factors were too slow over the last update: the tangent of this iterate is taken now and solved in
    // this iteration, rather than after one more update on the factors that just proved slow (a residual and a
    // back-substitution that gain little). With factors at hand only the law's tangent is updated (GMRES applies it
    // point by point); otherwise the matrix is assembled, with the residual again (the same iterate). The next
    // iteration goes back to the kept factors and is watched afresh.
    bool refreshed = false;
    if (!constant_tangent && reuse &&
        kept_factors_too_slow(r, last, last, 1, target, it, options_.refactor_contraction,
                              options_.max_newton_iterations)) {
      t0 = std::chrono::steady_clock::now();
      try {
        if (linear_solver_->has_factors()) {
          // GMRES on the kept factors applies this tangent point by point (apply_tangent), at about the cost of a
          // residual: only the law's tangent at each point is needed, not the matrix (1.3 s on lung_small).
          update_material(current_dt_, true);
          tangent_by_points_ = true;
          matrix_current_ = false;
          linear_solver_->invalidate();
        } else {
          assemble_system(true);
        }
      } catch (const std::runtime_error& e) {
        attempt.failure = e.what();
        break;
      }
      rec->assembly_seconds += seconds_since(t0);
      refreshed = true;
    }
    t0 = std::chrono::steady_clock::now();
    u_before = u_;
    try {
      solve(gmres_tolerance(r / reference, options_.newton_tolerance * reference / r));
    } catch (const std::runtime_error& e) {
      attempt.failure = e.what();
      break;
    }
    // Mix only updates of one fixed map: a back-substitution on the kept factors.
    last_mixed = reuse && !refreshed && !last_solve_prepared_ && last_linear_iterations_ == 0 && mixing.depth() > 0;
    if (last_mixed) {
      plain_update = u_ - u_before;
      u_ = u_before + mixing.next_update(u_before, plain_update);
      last_mixed = mixing.history() > 0;  // with no stored pair the update was the plain one
    } else {
      mixing.reset();
    }
    rec->solve_seconds += seconds_since(t0);
    rec->linear_iterations += last_linear_iterations_;
    rec->factorisations += last_solve_prepared_;
    ++rec->newton_iterations;
    ++attempt.iterations;
  }
  if (!attempt.converged()) {
    u_ = u_start;
    mixing_.reset();
    linear_solver_->forget_factors();  // factors of a failed iterate: never reuse them
    matrix_current_ = false;
  }
  return attempt;
}

void EfgModel::restart(std::vector<char> loaded_faces, VectorField traction, bool keep_factors) {
  if (!set_up_) throw std::logic_error("EfgModel::restart before setup_system");
  problem_.loaded_faces = std::move(loaded_faces);
  problem_.traction = std::move(traction);
  boundary_ = make_boundary_terms(problem_, surface_, alpha_);  // eq. 24's traction term for the new load
  stats_.loaded_area = boundary_.loaded_area;
  states_.assign(states_.size(), core::KelvinState{});
  for (core::Vector6& e : strain_) e.setZero();
  for (core::Vector6& s : stress_) s.setZero();
  u_.setZero();
  previous_start_.reset();
  mixing_.reset();
  residual_.setZero();
  external_.setZero();
  records_.clear();
  smallest_margin_ = core::SmallestMargin{};  // each run reports its own closest approach to the law's limit
  matrix_current_ = false;  // the factorisation (factorisation_, factorised_dt_) is kept for solve_step to reuse
  if (!keep_factors) linear_solver_->forget_factors();
}

void EfgModel::run(const StepObserver& observer) {
  setup_system();
  const int n = static_cast<int>(problem_.step_times.size());
  for (int step = 1; step <= n; ++step) {
    const StepRecord rec = solve_step(step);
    const int every = std::max(1, problem_.output_every);
    if (observer && (step % every == 0 || step == n)) observer(*this, rec);  // output_results
  }
}

Eigen::Vector3d EfgModel::displacement_at(const Eigen::Vector3d& x, int side) const {
  // A point next to a cut is on the lip given by the rule both models share (core::RuledSurface::side), unless
  // the caller names one.
  if (side == 0 && problem_.cut) side = problem_.cut->side(x);
  const MlsEvaluation e = mls_->evaluate(x, false, side);
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (int k = 0; k < e.size(); ++k) u += e.phi[k] * u_.segment<3>(3 * e.nodes[k]);  // eq. 7
  if (!u.allFinite())
    throw std::runtime_error(fmt::format("EfgModel: non-finite displacement at ({:.6g}, {:.6g}, {:.6g}) mm",
                                         1e3 * x.x(), 1e3 * x.y(), 1e3 * x.z()));
  return u;
}

core::PointMatrix EfgModel::displacements_at(const core::PointMatrix& points) const {
  if (!set_up_) throw std::logic_error("EfgModel::displacements_at before setup_system");
  core::PointMatrix u(points.rows(), 3);
  parallel_for(static_cast<int>(points.rows()), 256,
               [&](int p) { u.row(p) = displacement_at(points.row(p).transpose()).transpose(); });
  return u;
}

std::vector<core::Vector6> EfgModel::quadrature_strains() const { return strain_; }

}  // namespace meshless
