// MLS shape functions (paper §2, eqs. 1-8): weight, neighbour search, support radii, consistency, gradients,
// singular moment matrices and the weight-modifier hook of §4.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>

#include "meshless/mls/cubic_spline_weight.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"

namespace meshless {
namespace {

constexpr double kBox = 0.1;       // cube edge [m]
constexpr double kSpacing = 0.01;  // grid spacing [m]

/// (n)^3 grid of spacing `a` starting at the origin, each coordinate moved by U(-jitter*a, jitter*a).
core::PointMatrix make_grid(int n, double a, double jitter, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-jitter * a, jitter * a);
  core::PointMatrix p(n * n * n, 3);
  int row = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k, ++row) p.row(row) << i * a + u(gen), j * a + u(gen), k * a + u(gen);
  return p;
}

core::PointMatrix make_random_cloud(int n, double edge, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, edge);
  core::PointMatrix p(n, 3);
  for (int i = 0; i < n; ++i) p.row(i) << u(gen), u(gen), u(gen);
  return p;
}

std::vector<Eigen::Vector3d> random_points(int n, double lo, double hi, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Eigen::Vector3d> x(n);
  for (auto& xi : x) xi = Eigen::Vector3d(u(gen), u(gen), u(gen));
  return x;
}

/// Owns the node matrix and everything built on it (the search and shape functions reference the matrix, so
/// it must not move: always held through a unique_ptr).
struct Cloud {
  explicit Cloud(core::PointMatrix p, SupportRadiiParams params = {})
      : nodes(std::move(p)), search(nodes), radii(nodes, search, params), mls(nodes, radii, search) {}
  core::PointMatrix nodes;
  NodeSearch search;
  SupportRadii radii;
  MlsShapeFunctions mls;
};

// ------------------------------------------------------------------------------------------------ weight
// (eq. 8)

TEST(CubicSplineWeight, ValuesAndSmoothness) {
  EXPECT_DOUBLE_EQ(cubic_spline_weight(0.0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(cubic_spline_weight_with_slope(0.0).w, 2.0 / 3.0);
  EXPECT_EQ(cubic_spline_weight_with_slope(0.0).dw_ds, 0.0);
  EXPECT_DOUBLE_EQ(cubic_spline_weight(0.5), 1.0 / 6.0);
  EXPECT_EQ(cubic_spline_weight(1.0), 0.0);
  EXPECT_EQ(cubic_spline_weight(1.5), 0.0);
  EXPECT_EQ(cubic_spline_weight_with_slope(2.0).dw_ds, 0.0);

  // Continuity of w and w' across the knots s = 1/2 and s = 1: one-sided limits agree to O(eps).
  const double eps = 1e-9;
  for (double knot : {0.5, 1.0}) {
    const WeightAndSlope left = cubic_spline_weight_with_slope(knot - eps);
    const WeightAndSlope right = cubic_spline_weight_with_slope(knot + eps);
    EXPECT_NEAR(left.w, right.w, 1e-8) << "s = " << knot;
    EXPECT_NEAR(left.dw_ds, right.dw_ds, 1e-7) << "s = " << knot;
  }
  EXPECT_DOUBLE_EQ(cubic_spline_weight_with_slope(0.5).dw_ds, -1.0);
  EXPECT_NEAR(cubic_spline_weight_with_slope(1.0 - 1e-9).dw_ds, 0.0, 1e-15);

  // The slope is the derivative of the value (central differences).
  for (double s : {0.1, 0.3, 0.49, 0.51, 0.7, 0.95}) {
    const double h = 1e-6;
    const double fd = (cubic_spline_weight(s + h) - cubic_spline_weight(s - h)) / (2 * h);
    EXPECT_NEAR(cubic_spline_weight_with_slope(s).dw_ds, fd, 1e-8) << "s = " << s;
    EXPECT_EQ(cubic_spline_weight_with_slope(s).w, cubic_spline_weight(s));
  }
}

// ---------------------------------------------------------------------------------------------- node search

TEST(NodeSearch, MatchesBruteForce) {
  const core::PointMatrix p = make_random_cloud(3000, kBox, 11);
  const NodeSearch search(p);
  std::mt19937 gen(13);
  std::uniform_real_distribution<double> radius_dist(0.005, 0.025);
  Eigen::VectorXd radii(p.rows());
  for (int i = 0; i < p.rows(); ++i) radii[i] = radius_dist(gen);
  std::vector<NodeHit> hits;
  for (const Eigen::Vector3d& x : random_points(100, -0.01, kBox + 0.01, 12)) {
    const Eigen::VectorXd d2 = (p.rowwise() - x.transpose()).rowwise().squaredNorm();
    std::vector<int> order(p.rows());
    for (int i = 0; i < p.rows(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return d2[a] < d2[b]; });

    std::vector<double> knn_d2;
    const std::vector<int> knn = search.nearest(x, 12, &knn_d2);
    ASSERT_EQ(knn.size(), 12u);
    for (int j = 0; j < 12; ++j) {
      EXPECT_EQ(knn[j], order[j]);
      EXPECT_NEAR(knn_d2[j], d2[order[j]], 1e-18);
    }

    const double radius = 0.017;
    std::set<int> brute;
    for (int i = 0; i < p.rows(); ++i)
      if (d2[i] < radius * radius) brute.insert(i);
    const std::vector<int> found = search.within_radius(x, radius);
    EXPECT_EQ(std::set<int>(found.begin(), found.end()), brute);
    EXPECT_EQ(found.size(), brute.size());  // no duplicates
    for (size_t j = 1; j < found.size(); ++j) EXPECT_LE(d2[found[j - 1]], d2[found[j]]);

    // Nodes whose own sphere contains x.
    std::set<int> brute_covering;
    for (int i = 0; i < p.rows(); ++i)
      if (d2[i] < radii[i] * radii[i]) brute_covering.insert(i);
    search.covering(x, radii, radii.maxCoeff(), &hits);
    std::set<int> covering;
    for (const NodeHit& hit : hits) {
      covering.insert(hit.node);
      EXPECT_NEAR(hit.distance_sq, d2[hit.node], 1e-18);
    }
    EXPECT_EQ(covering, brute_covering);
    EXPECT_EQ(hits.size(), brute_covering.size());
  }
  EXPECT_EQ(search.nearest(Eigen::Vector3d::Zero(), 5000).size(), 3000u);  // k larger than the cloud
}

// --------------------------------------------------------------------------------------------- support radii

TEST(SupportRadii, KthNeighbourTimesDilation) {
  // Regular grid: the 6 face neighbours sit at a, the next 12 at a*sqrt(2).
  auto cloud = std::make_unique<Cloud>(make_grid(5, kSpacing, 0.0, 0), SupportRadiiParams{2.0, 6});
  const int centre = 2 * 25 + 2 * 5 + 2;
  EXPECT_NEAR(cloud->radii.radius(centre), 2.0 * kSpacing, 1e-15);
  auto cloud8 = std::make_unique<Cloud>(make_grid(5, kSpacing, 0.0, 0), SupportRadiiParams{2.0, 8});
  EXPECT_NEAR(cloud8->radii.radius(centre), 2.0 * std::sqrt(2.0) * kSpacing, 1e-15);
  // A corner node has 3 neighbours at a, 3 at a*sqrt(2), 1 at a*sqrt(3), then 3 at 2a.
  EXPECT_NEAR(cloud8->radii.radius(0), 2.0 * 2.0 * kSpacing, 1e-15);
  EXPECT_NEAR(cloud8->radii.max_radius(), cloud8->radii.radii().maxCoeff(), 0.0);
  EXPECT_TRUE(cloud8->radii.covers(centre, cloud8->nodes, Eigen::Vector3d(0.02, 0.02, 0.02 + 0.028)));
  EXPECT_FALSE(cloud8->radii.covers(centre, cloud8->nodes, Eigen::Vector3d(0.02, 0.02, 0.02 + 0.0283)));

  // Brute-force check on an irregular cloud with the default parameters.
  const core::PointMatrix p = make_random_cloud(500, kBox, 5);
  const NodeSearch search(p);
  const SupportRadii radii(p, search);
  EXPECT_EQ(radii.params().k, 8);
  EXPECT_EQ(radii.params().d_max, 2.0);
  for (int i = 0; i < p.rows(); ++i) {
    Eigen::VectorXd d = (p.rowwise() - p.row(i)).rowwise().norm();
    std::sort(d.data(), d.data() + d.size());
    ASSERT_EQ(d[0], 0.0);
    EXPECT_NEAR(radii.radius(i), 2.0 * d[8], 1e-16);
  }
}

TEST(SupportRadii, RejectsDegenerateInput) {
  core::PointMatrix p = make_random_cloud(5, kBox, 1);
  const NodeSearch search(p);
  EXPECT_THROW(SupportRadii(p, search), std::invalid_argument);  // 5 nodes < k + 1
  core::PointMatrix dup = make_random_cloud(20, kBox, 1);
  for (int i = 1; i < 20; i += 2) dup.row(i) = dup.row(0);  // node 0 has 10 coincident copies
  const NodeSearch dup_search(dup);
  EXPECT_THROW(SupportRadii(dup, dup_search), std::invalid_argument);
}

// ----------------------------------------------------------------------------------- consistency (eqs. 1-7)

/// Largest violation of the MLS consistency conditions over a set of points, each made dimensionless:
/// |sum phi - 1|, |sum phi_i x_i - X| / a, a |sum d phi|, |sum d_k phi_i x_i - delta|.
struct ConsistencyErrors {
  double partition = 0, linear = 0, gradient_partition = 0, gradient_linear = 0;
  double linear_absolute = 0;  // [m], before dividing by the spacing
  double min_rcond = 1;
};

ConsistencyErrors check_consistency(const Cloud& cloud, const std::vector<Eigen::Vector3d>& points) {
  ConsistencyErrors e;
  MlsEvaluation ev;
  for (const Eigen::Vector3d& x : points) {
    cloud.mls.evaluate(x, true, &ev);
    EXPECT_TRUE(ev.phi.allFinite() && ev.dphi.allFinite());
    EXPECT_EQ(ev.dphi.cols(), ev.size());
    Eigen::Matrix<double, Eigen::Dynamic, 3> xi(ev.size(), 3);
    for (int j = 0; j < ev.size(); ++j) xi.row(j) = cloud.nodes.row(ev.nodes[j]);
    e.partition = std::max(e.partition, std::abs(ev.phi.sum() - 1.0));
    const Eigen::Vector3d lin = xi.transpose() * ev.phi - x;  // sum phi_i x_i - X, raw coordinates
    e.linear_absolute = std::max(e.linear_absolute, lin.cwiseAbs().maxCoeff());
    e.linear = std::max(e.linear, lin.cwiseAbs().maxCoeff() / kSpacing);
    e.gradient_partition =
        std::max(e.gradient_partition, kSpacing * ev.dphi.rowwise().sum().cwiseAbs().maxCoeff());
    const Eigen::Matrix3d grad_lin = ev.dphi * xi;  // (k, m) = sum_i d_k phi_i x_i,m, raw coordinates
    e.gradient_linear =
        std::max(e.gradient_linear, (grad_lin - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    e.min_rcond = std::min(e.min_rcond, ev.rcond);
  }
  return e;
}

void expect_consistent(const char* name, const ConsistencyErrors& e) {
  std::cout << name << ": max |sum phi - 1| = " << e.partition << ", |sum phi x - X| = " << e.linear_absolute
            << " m (" << e.linear << " spacings), spacing*|sum dphi| = " << e.gradient_partition
            << ", |sum dphi x - I| = " << e.gradient_linear << ", min rcond = " << e.min_rcond << "\n";
  EXPECT_LT(e.partition, 1e-12);
  EXPECT_LT(e.linear, 1e-12);
  EXPECT_LT(e.linear_absolute, 1e-14);
  EXPECT_LT(e.gradient_partition, 1e-12);
  EXPECT_LT(e.gradient_linear, 1e-12);
  EXPECT_GT(e.min_rcond, 1e-6);
}

TEST(MlsShapeFunctions, ConsistencyOnRegularGrid) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.0, 0));
  const auto points = random_points(200, 0.5 * kSpacing, kBox - 0.5 * kSpacing, 21);
  expect_consistent("regular grid", check_consistency(*cloud, points));
  // Exactly on nodes too (r = 0 in the weight gradient).
  std::vector<Eigen::Vector3d> at_nodes;
  for (int i = 0; i < cloud->nodes.rows(); i += 37) at_nodes.push_back(cloud->nodes.row(i).transpose());
  expect_consistent("regular grid, at nodes", check_consistency(*cloud, at_nodes));
}

TEST(MlsShapeFunctions, ConsistencyOnPerturbedCloud) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  const auto points = random_points(200, 0.5 * kSpacing, kBox - 0.5 * kSpacing, 22);
  expect_consistent("perturbed cloud", check_consistency(*cloud, points));
}

TEST(MlsShapeFunctions, ConsistencyOnUniformRandomCloudIncludingBoundary) {
  auto cloud = std::make_unique<Cloud>(make_random_cloud(1331, kBox, 77));
  const auto points = random_points(200, 0.0, kBox, 23);  // corners and faces included
  expect_consistent("uniform random cloud", check_consistency(*cloud, points));
}

// ------------------------------------------------------------------------------------------------- gradients

/// Largest |dphi - central difference| over nodes and directions, relative to the largest |dphi| at the
/// point.
double max_gradient_error(const MlsShapeFunctions& mls, const std::vector<Eigen::Vector3d>& points) {
  const double step = 1e-6;  // [m]; truncation ~ step^2 |phi'''| ~ 1e-12 / a^3, round-off ~ 1e-16 / step
  double worst = 0.0;
  for (const Eigen::Vector3d& x : points) {
    const MlsEvaluation ev = mls.evaluate(x, true);
    const double scale = ev.dphi.cwiseAbs().maxCoeff();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d dx = step * Eigen::Vector3d::Unit(k);
      const MlsEvaluation plus = mls.evaluate(x + dx, false), minus = mls.evaluate(x - dx, false);
      std::map<int, double> fd;  // node -> central difference (nodes entering/leaving count as phi = 0)
      for (int j = 0; j < plus.size(); ++j) fd[plus.nodes[j]] += plus.phi[j] / (2 * step);
      for (int j = 0; j < minus.size(); ++j) fd[minus.nodes[j]] -= minus.phi[j] / (2 * step);
      for (int j = 0; j < ev.size(); ++j) {
        worst = std::max(worst, std::abs(ev.dphi(k, j) - fd[ev.nodes[j]]) / scale);
        fd.erase(ev.nodes[j]);
      }
      for (const auto& [node, value] : fd)
        worst = std::max(worst, std::abs(value) / scale);  // dphi = 0 there
    }
  }
  return worst;
}

TEST(MlsShapeFunctions, GradientsMatchFiniteDifferences) {
  auto grid = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.0, 0));
  auto perturbed = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  const auto points = random_points(40, 0.5 * kSpacing, kBox - 0.5 * kSpacing, 31);
  const double e_grid = max_gradient_error(grid->mls, points);
  const double e_perturbed = max_gradient_error(perturbed->mls, points);
  std::cout << "gradient vs central differences (relative): grid " << e_grid << ", perturbed " << e_perturbed
            << "\n";
  EXPECT_LT(e_grid, 1.2e-8);       // Measured 6.06e-9 (the step's truncation error, deterministic)
  EXPECT_LT(e_perturbed, 2.5e-8);  // Measured 1.22e-8
}

TEST(MlsShapeFunctions, WithoutGradientsGivesSameValues) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  for (const Eigen::Vector3d& x : random_points(20, 0.0, kBox, 41)) {
    const MlsEvaluation a = cloud->mls.evaluate(x, true), b = cloud->mls.evaluate(x, false);
    EXPECT_EQ(a.nodes, b.nodes);
    EXPECT_EQ(b.dphi.cols(), 0);
    EXPECT_LT((a.phi - b.phi).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_TRUE(std::is_sorted(a.nodes.begin(), a.nodes.end()));
    for (int j = 0; j < a.size(); ++j) EXPECT_TRUE(cloud->radii.covers(a.nodes[j], cloud->nodes, x));
  }
}

// ---------------------------------------------------------------------------------------- singular A(X)

TEST(MlsShapeFunctions, FarPointThrowsWithNeighbourCount) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  try {
    (void)cloud->mls.evaluate(Eigen::Vector3d(1.0, 1.0, 1.0), true);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("0 covering neighbour"), std::string::npos) << msg;
    EXPECT_NE(msg.find("(1000, 1000, 1000) mm"), std::string::npos) << msg;
    EXPECT_EQ(e.num_covering(), 0);
    EXPECT_EQ(e.point(), Eigen::Vector3d(1.0, 1.0, 1.0));
  }
  // Is-a runtime_error, so generic handlers see it.
  EXPECT_THROW((void)cloud->mls.evaluate(Eigen::Vector3d(-0.5, 0.05, 0.05), false), std::runtime_error);
  EXPECT_THROW((void)cloud->mls.evaluate(Eigen::Vector3d(NAN, 0.05, 0.05), false), std::invalid_argument);
}

TEST(MlsShapeFunctions, CoplanarCloudThrowsWithNeighbourCount) {
  // An 11 x 11 sheet in z = 0: the z column of A(X) vanishes.
  core::PointMatrix sheet(121, 3);
  for (int i = 0; i < 11; ++i)
    for (int j = 0; j < 11; ++j) sheet.row(11 * i + j) << i * kSpacing, j * kSpacing, 0.0;
  auto cloud = std::make_unique<Cloud>(sheet);
  const Eigen::Vector3d x(0.0512, 0.0437, 0.0);
  const int covering = [&] {
    int c = 0;
    for (int i = 0; i < sheet.rows(); ++i) c += cloud->radii.covers(i, cloud->nodes, x);
    return c;
  }();
  ASSERT_GE(covering, 4);
  try {
    (void)cloud->mls.evaluate(x, true);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& e) {
    const std::string msg = e.what();
    std::cout << msg << "\n";
    EXPECT_NE(msg.find(std::to_string(covering) + " covering neighbour"), std::string::npos) << msg;
    EXPECT_NE(msg.find("(51.2, 43.7, 0) mm"), std::string::npos) << msg;
    EXPECT_EQ(e.num_covering(), covering);
    EXPECT_LT(e.rcond(), 1e-10);
  }
  // Slightly off the sheet it is just as singular: the nodes still span no volume.
  EXPECT_THROW((void)cloud->mls.evaluate(Eigen::Vector3d(0.05, 0.05, 0.001), false), SingularMomentMatrix);
}

TEST(MlsShapeFunctions, ThreeNodesThrow) {
  core::PointMatrix p(3, 3);
  p << 0, 0, 0, 0.01, 0, 0, 0, 0.01, 0;
  const NodeSearch search(p);
  const SupportRadii radii(Eigen::VectorXd::Constant(3, 0.05));
  const MlsShapeFunctions mls(p, radii, search);
  try {
    (void)mls.evaluate(Eigen::Vector3d(0.003, 0.003, 0.001), false);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& e) {
    EXPECT_NE(std::string(e.what()).find("3 covering neighbour"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------------------- weight modifier (§4)

TEST(MlsShapeFunctions, ModifierHidesNodesAcrossACut) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  const double cut = 0.05;
  const core::PointMatrix& nodes = cloud->nodes;
  int calls_with_grad = 0;
  // Nodes beyond the plane x = cut are invisible from points before it (a crude visibility criterion).
  cloud->mls.set_weight_modifier([&](int node, const Eigen::Vector3d& x, int, Eigen::Vector3d* grad) {
    if (grad != nullptr) {
      grad->setZero();
      ++calls_with_grad;
    }
    return (nodes(node, 0) > cut && x.x() < cut) ? 0.0 : 1.0;
  });
  ASSERT_TRUE(cloud->mls.has_weight_modifier());
  int checked = 0;
  for (Eigen::Vector3d x : random_points(200, 0.5 * kSpacing, kBox - 0.5 * kSpacing, 51)) {
    x.x() =
        0.5 * kSpacing + (x.x() - 0.5 * kSpacing) * (cut - 0.5 * kSpacing) / (kBox - kSpacing);  // x < cut
    ASSERT_LT(x.x(), cut);
    const MlsEvaluation ev = cloud->mls.evaluate(x, true);
    double hidden_phi = 0.0;
    bool near_cut = false;
    for (int j = 0; j < ev.size(); ++j)
      if (nodes(ev.nodes[j], 0) > cut) hidden_phi = std::max(hidden_phi, std::abs(ev.phi[j]));
    for (int i = 0; i < nodes.rows(); ++i) near_cut |= nodes(i, 0) > cut && cloud->radii.covers(i, nodes, x);
    checked += near_cut;
    EXPECT_EQ(hidden_phi, 0.0);
    EXPECT_LT(std::abs(ev.phi.sum() - 1.0), 1e-12);
    EXPECT_LT(kSpacing * ev.dphi.rowwise().sum().cwiseAbs().maxCoeff(), 1e-12);
    Eigen::Vector3d lin = -x;
    for (int j = 0; j < ev.size(); ++j) lin += ev.phi[j] * nodes.row(ev.nodes[j]).transpose();
    EXPECT_LT(lin.cwiseAbs().maxCoeff() / kSpacing, 1e-12);
  }
  EXPECT_GT(checked, 50);  // many points really had hidden nodes in their support
  EXPECT_GT(calls_with_grad, 0);

  cloud->mls.set_weight_modifier(nullptr);
  EXPECT_FALSE(cloud->mls.has_weight_modifier());
  const MlsEvaluation ev = cloud->mls.evaluate(Eigen::Vector3d(0.049, 0.05, 0.05), false);
  bool sees_beyond = false;
  for (int node : ev.nodes) sees_beyond |= nodes(node, 0) > cut;
  EXPECT_TRUE(sees_beyond);
}

TEST(MlsShapeFunctions, SmoothModifierGradientsMatchFiniteDifferences) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.4, 2024));
  const core::PointMatrix& nodes = cloud->nodes;
  // h_i(X) = 0.55 + 0.45 sin(40 X.x + 7 node_x) cos(30 X.z): smooth, in [0.1, 1], differs from node to node.
  cloud->mls.set_weight_modifier([&](int node, const Eigen::Vector3d& x, int, Eigen::Vector3d* grad) {
    const double a = 40.0 * x.x() + 7.0 * nodes(node, 0) / kSpacing, b = 30.0 * x.z();
    if (grad != nullptr)
      *grad = Eigen::Vector3d(0.45 * 40.0 * std::cos(a) * std::cos(b), 0.0,
                              -0.45 * 30.0 * std::sin(a) * std::sin(b));
    return 0.55 + 0.45 * std::sin(a) * std::cos(b);
  });
  const auto points = random_points(30, 0.5 * kSpacing, kBox - 0.5 * kSpacing, 61);
  const double err = max_gradient_error(cloud->mls, points);
  std::cout << "gradient vs central differences with a smooth modifier (relative): " << err << "\n";
  EXPECT_LT(err, 3e-8);  // Measured 1.43e-8 (the step's truncation error, deterministic)
  expect_consistent("perturbed cloud, smooth modifier", check_consistency(*cloud, points));
}

TEST(MlsShapeFunctions, ModifierOutsideUnitIntervalIsRejected) {
  auto cloud = std::make_unique<Cloud>(make_grid(11, kSpacing, 0.0, 0));
  cloud->mls.set_weight_modifier([](int, const Eigen::Vector3d&, int, Eigen::Vector3d*) { return 1.5; });
  EXPECT_THROW((void)cloud->mls.evaluate(Eigen::Vector3d(0.05, 0.05, 0.05), false), std::domain_error);
  cloud->mls.set_weight_modifier([](int, const Eigen::Vector3d&, int, Eigen::Vector3d*) { return NAN; });
  EXPECT_THROW((void)cloud->mls.evaluate(Eigen::Vector3d(0.05, 0.05, 0.05), false), std::domain_error);
}

}  // namespace
}  // namespace meshless
