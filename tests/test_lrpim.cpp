// Tests of the LRPIM model (meshless/lrpim/, docs/LRPIM.md §3-4): the surface body's rays against the box's analytic
// ones and through a concave body, the boundary triangles' rule, RPIM invariants and the Kronecker delta, the
// singular moment matrix, the linear patch test (on the box's 12 triangles and on the cloud's own boundary
// triangles), the Timoshenko cantilever's rates and the closed-form creep at k = 0 and k != 0. Bounds sit near the
// values reached (printed), so a lost digit or order fails.
#include <gtest/gtest.h>

#include <cstdlib>

#include <functional>

#include <cmath>
#include <iostream>

#include <random>
#include <sstream>

#include "core/convergence_rate.hpp"
#include "meshless/lrpim/box_body.hpp"
#include "meshless/lrpim/local_quadrature.hpp"
#include "meshless/lrpim/lrpim_model.hpp"
#include "meshless/solvers/kept_factors.hpp"
#include "meshless/lrpim/surface_body.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "meshless/lrpim/lrpim_verification.hpp"
#include "meshless/lrpim/rpim_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/verification/verification_problems.hpp"

using namespace meshless::lrpim;

TEST(Lrpim, GaussLegendreIntegratesItsDegree) {
  std::vector<double> x, w;
  for (int n : {1, 3, 4, 8}) {
    gauss_legendre(n, &x, &w);
    for (int deg = 0; deg <= 2 * n - 1; ++deg) {
      double s = 0.0;
      for (int i = 0; i < n; ++i) s += w[i] * std::pow(x[i], deg);
      EXPECT_NEAR(s, deg % 2 ? 0.0 : 2.0 / (deg + 1), 1e-14) << "n " << n << " degree " << deg;
    }
  }
}

TEST(Lrpim, SurfaceBodyRaysMatchTheBoxToRoundOff) {
  // A box given as its 12 triangles: every ray's piece inside must be the box's analytic [0, exit], from nodes
  // inside, on faces, on edges and at corners (rays leaving through the surface have none), and the sphere rule's
  // points must be the box rule's.
  const BoxBody box{Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.05, 0.03, 0.02)};
  const SurfaceBody body = SurfaceBody::from_box(box);
  const double h = 0.01, r_q = 1.5 * h;
  core::PointMatrix points = meshless::make_box_mesh(box.lo, box.hi, 5, 3, 2, {}, 0.2, 3).vertices;
  std::mt19937 gen(4);
  std::normal_distribution<double> normal;
  double max_reach_error = 0.0, max_point_error = 0.0;
  int rays = 0, empty = 0, surface_nodes = 0;
  std::vector<RaySegment> pieces;
  LocalQuadratureRule rule;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    const LocalSurface local(body, x, r_q, 1e-9 * h);
    surface_nodes += local.on_surface();
    for (int k = 0; k < 200; ++k, ++rays) {
      const Eigen::Vector3d d = Eigen::Vector3d(normal(gen), normal(gen), normal(gen)).normalized();
      const double reach = std::min(r_q, box.exit_distance(x, d));
      local.ray_segments(d, r_q, &pieces);
      if (reach == 0.0) {
        ++empty;
        EXPECT_TRUE(pieces.empty()) << "node " << i << " ray " << k;
        continue;
      }
      ASSERT_EQ(pieces.size(), 1u) << "node " << i << " ray " << k;
      EXPECT_EQ(pieces[0].begin, 0.0);
      max_reach_error = std::max(max_reach_error, std::abs(pieces[0].end - reach) / r_q);
    }
    const std::vector<LocalPoint> a = sphere_points(x, r_q, box, rule), b = sphere_points(x, r_q, local, rule);
    ASSERT_EQ(a.size(), b.size()) << "node " << i;
    for (size_t q = 0; q < a.size(); ++q)
      max_point_error = std::max({max_point_error, (a[q].x - b[q].x).norm() / r_q,
                                  std::abs(a[q].weight - b[q].weight) / (r_q * r_q * r_q)});
  }
  std::cout << rays << " rays from " << points.rows() << " nodes (" << surface_nodes << " on the surface, " << empty
            << " rays leaving at once): largest reach error " << max_reach_error << " r_q, sphere points "
            << max_point_error << "\n";
  EXPECT_GT(surface_nodes, 50);
  EXPECT_GT(empty, 1000);
  EXPECT_LT(max_reach_error, 1e-14);
  EXPECT_LT(max_point_error, 1e-14);
}

// The U-shaped prism of the concave test: the polygon (0,0) (3,0) (3,3) (2,3) (2,1) (1,1) (1,3) (0,3) (cm,
// counter-clockwise) extruded over 0 <= z <= 1 cm; caps split into six triangles each.
SurfaceBody u_shaped_body() {
  const double cm = 0.01;
  const double poly[8][2] = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  core::PointMatrix v(16, 3);
  for (int i = 0; i < 8; ++i) {
    v.row(i) << poly[i][0] * cm, poly[i][1] * cm, 0.0;
    v.row(8 + i) << poly[i][0] * cm, poly[i][1] * cm, cm;
  }
  const int cap[6][3] = {{0, 1, 4}, {0, 4, 5}, {1, 2, 3}, {1, 3, 4}, {0, 5, 6}, {0, 6, 7}};
  core::TriMatrix t(28, 3);
  int r = 0;
  for (const auto& c : cap) {
    t.row(r++) << 8 + c[0], 8 + c[1], 8 + c[2];  // top, normal +z
    t.row(r++) << c[0], c[2], c[1];              // bottom, normal -z
  }
  for (int i = 0; i < 8; ++i) {
    const int j = (i + 1) % 8;
    t.row(r++) << i, j, 8 + j;
    t.row(r++) << i, 8 + j, 8 + i;
  }
  return SurfaceBody(v, t, std::vector<int>(28, 0));
}

TEST(Lrpim, SurfaceBodyRaysLeaveAndReenterAConcaveBody) {
  const double cm = 0.01;
  const SurfaceBody body = u_shaped_body();
  std::vector<RaySegment> s;
  auto expect_pieces = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& d, double r_max,
                           const std::vector<std::pair<double, double>>& expected) {
    const LocalSurface local(body, x, r_max, 1e-9 * cm);
    local.ray_segments(d.normalized(), r_max, &s);
    ASSERT_EQ(s.size(), expected.size()) << "from (" << x.transpose() / cm << ") cm along (" << d.transpose() << ")";
    for (size_t k = 0; k < s.size(); ++k) {
      EXPECT_NEAR(s[k].begin, expected[k].first, 1e-15);
      EXPECT_NEAR(s[k].end, expected[k].second, 1e-15);
    }
  };
  // From inside the left arm across the notch into the right arm: out at x = 1, in at x = 2, out at x = 3.
  expect_pieces(Eigen::Vector3d(0.5, 2.5, 0.5) * cm, Eigen::Vector3d::UnitX(), 3 * cm,
                {{0.0, 0.5 * cm}, {1.5 * cm, 2.5 * cm}});
  expect_pieces(Eigen::Vector3d(0.5, 2.5, 0.5) * cm, Eigen::Vector3d::UnitX(), 2 * cm,
                {{0.0, 0.5 * cm}, {1.5 * cm, 2.0 * cm}});
  // From the notch's face x = 1: leaving at once, re-entering at x = 2; or inward, to x = 0.
  expect_pieces(Eigen::Vector3d(1.0, 2.0, 0.5) * cm, Eigen::Vector3d::UnitX(), 3 * cm, {{1.0 * cm, 2.0 * cm}});
  expect_pieces(Eigen::Vector3d(1.0, 2.0, 0.5) * cm, -Eigen::Vector3d::UnitX(), 3 * cm, {{0.0, 1.0 * cm}});
  // From the re-entrant edge (1, 1): into the notch (outside) then through the right arm from x = 2 to 3; or into
  // the body's corner region.
  const double l = std::sqrt(5.0) * cm;
  expect_pieces(Eigen::Vector3d(1.0, 1.0, 0.5) * cm, Eigen::Vector3d(2, 1, 0), 1.5 * l, {{0.5 * l, l}});
  expect_pieces(Eigen::Vector3d(1.0, 1.0, 0.5) * cm, Eigen::Vector3d(-2, -1, 0), 1.5 * l, {{0.0, 0.5 * l}});
  // From the top-cap vertex (1, 1, 1) at the re-entrant corner: upwards leaves at once; down into the U's base
  // crosses the body to z = 0.
  expect_pieces(Eigen::Vector3d(1.0, 1.0, 1.0) * cm, Eigen::Vector3d(0.3, 0.2, 1.0), 2 * cm, {});
  expect_pieces(Eigen::Vector3d(1.0, 1.0, 1.0) * cm, Eigen::Vector3d(-0.3, -0.2, -1.0), 2 * cm,
                {{0.0, std::sqrt(1.13) * cm}});
  // From the notch's face below the corner: through the notch, into the right arm at x = 2, out at x = 3.
  expect_pieces(Eigen::Vector3d(1.0, 1.5, 0.5) * cm, Eigen::Vector3d::UnitX(), 3 * cm, {{1.0 * cm, 2.0 * cm}});
}

TEST(Lrpim, BoundaryTrianglesIntegrateTheTestFunction) {
  // int v dA over a plane at distance delta from the node: 2 pi r_q^2 int_{delta/r_q}^1 w(s) s ds (rho drho =
  // r_q^2 s ds), exact by Gauss on the spline's two polynomial pieces. The plane is a 10 r_q square as two triangles,
  // and the same square as 200 small triangles (the rule must not care how the surface is cut up).
  const double r_q = 0.015;
  LocalQuadratureRule rule;
  std::vector<double> gx, gw;
  gauss_legendre(8, &gx, &gw);
  auto exact = [&](double delta) {
    double sum = 0.0;
    auto piece = [&](double a, double b) {
      for (size_t k = 0; k < gx.size(); ++k) {
        const double s = 0.5 * (a + b) + 0.5 * (b - a) * gx[k];
        sum += 0.5 * (b - a) * gw[k] * (s <= 0.5 ? 2.0 / 3 - 4 * s * s + 4 * s * s * s
                                                 : 4.0 / 3 - 4 * s + 4 * s * s - 4.0 / 3 * s * s * s) * s;
      }
    };
    const double s0 = delta / r_q;
    if (s0 < 0.5) piece(s0, 0.5);
    piece(std::max(s0, 0.5), 1.0);
    return 2.0 * M_PI * r_q * r_q * sum;
  };
  double worst_coarse = 0.0, worst_fine = 0.0;
  for (double delta : {0.0, 0.2, 0.45, 0.7, 0.95}) {
    const Eigen::Vector3d c(0.13 * r_q, -0.31 * r_q, delta * r_q);
    const double e = exact(delta * r_q);
    auto integrate = [&](int n) {
      double sum = 0.0;
      const double a = 5.0 * r_q, step = 2.0 * a / n;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const Eigen::Vector3d p00(-a + i * step, -a + j * step, 0.0), p10 = p00 + Eigen::Vector3d(step, 0, 0),
                                p01 = p00 + Eigen::Vector3d(0, step, 0), p11 = p10 + Eigen::Vector3d(0, step, 0);
          for (const LocalPoint& p : triangle_points(c, r_q, p00, p10, p11, rule)) sum += p.weight * p.v;
          for (const LocalPoint& p : triangle_points(c, r_q, p00, p11, p01, rule)) sum += p.weight * p.v;
        }
      return sum;
    };
    const double coarse = std::abs(integrate(1) - e) / exact(0.0), fine = std::abs(integrate(10) - e) / exact(0.0);
    std::cout << "delta " << delta << " r_q: int v dA error " << coarse << " (2 triangles), " << fine
              << " (200 triangles), of int v dA at delta 0\n";
    worst_coarse = std::max(worst_coarse, coarse);
    worst_fine = std::max(worst_fine, fine);
  }
  EXPECT_LT(worst_coarse, 3e-6);  // 1.3e-6 (delta 0, the node on the plane)
  EXPECT_LT(worst_fine, 1e-6);    // 3.3e-7
}

TEST(Lrpim, RpimShapeFunctionsReproduceLinearFieldsAndInterpolate) {
  const RpimInvariantReport r = rpim_invariants();
  std::cout << "RPIM (q 1.03, alpha_c 4, 20 nodes) on " << r.num_nodes << " nodes: partition " << r.max_partition_error
            << ", reproduction " << r.max_reproduction_error << ", gradient sum " << r.max_gradient_sum
            << ", gradient reproduction " << r.max_gradient_reproduction << ", Kronecker delta "
            << r.max_kronecker_error << ", smallest rcond " << r.min_rcond << ", smallest spread " << r.min_spread
            << " d_c^2\n";
  // At about ten times what is measured (`tissue verify lrpim` keeps its looser pass bounds, lrpim.md).
  EXPECT_LT(r.max_partition_error, 1e-14);        // 1.22e-15
  EXPECT_LT(r.max_reproduction_error, 1e-13);     // 1.19e-14
  EXPECT_LT(r.max_gradient_sum, 2e-14);           // 1.78e-15
  EXPECT_LT(r.max_gradient_reproduction, 2e-13);  // 1.88e-14
  EXPECT_LT(r.max_kronecker_error, 3e-12);        // 2.77e-13
  EXPECT_GT(r.min_rcond, 1e-10);                  // 4.3e-9: the flat MQ, far above min_rcond
  // A healthy support is far from the rank test (1e-6): the jittered cloud's smallest spread is 0.1898 d_c^2, held to
  // its measured value so that a change in how the spread is computed shows.
  EXPECT_GT(r.min_spread, 1e5 * RpimParameters{}.min_spread);
  EXPECT_NEAR(r.min_spread, 0.1898, 0.0005);
}

TEST(Lrpim, SingularMomentMatrixIsReportedNotNaN) {
  // 25 nodes in the plane z = 0: P = [1 x y z] has a zero column in z, so G is singular.
  core::PointMatrix nodes(25, 3);
  for (int i = 0; i < 25; ++i) nodes.row(i) << 0.01 * (i % 5), 0.01 * (i / 5), 0.0;
  meshless::NodeSearch search(nodes);
  RpimShapeFunctions rpim(nodes, search, 0.01);
  const Eigen::Vector3d x(0.012, 0.021, 0.0);
  try {
    rpim.evaluate(x, true);
    FAIL() << "a coplanar support must throw";
  } catch (const SingularRpimMatrix& e) {
    EXPECT_EQ(e.num_nodes(), 20);
    EXPECT_TRUE(e.point().isApprox(x));
    // The LU's rcond estimate would not flag the exact singularity (it stayed at ~1e-8); the rank test of P does,
    // before G is factorised.
    EXPECT_TRUE(std::isnan(e.rcond()));
    EXPECT_LT(e.spread(), 1e-20);
    EXPECT_NE(std::string(e.what()).find("(12, 21, 0) mm"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_spread"), std::string::npos) << e.what();
  }
  // Nearly coplanar: the same nodes 1e-4 d_c off the plane. The LU solves this support (rcond printed) into
  // functions dominated by round-off; the rank test refuses it.
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> off(-1e-6, 1e-6);
  for (int i = 0; i < 25; ++i) nodes(i, 2) = off(gen);
  meshless::NodeSearch near_search(nodes);
  RpimParameters no_rank_test;
  no_rank_test.min_spread = 0.0;
  const RpimEvaluation unguarded = RpimShapeFunctions(nodes, near_search, 0.01, no_rank_test).evaluate(x, true);
  std::cout << "nearly coplanar support: rcond " << unguarded.rcond << ", spread " << unguarded.spread
            << " d_c^2, |grad phi| up to " << unguarded.dphi.cwiseAbs().maxCoeff() * 0.01 << " / d_c\n";
  EXPECT_GT(unguarded.rcond, RpimParameters{}.min_rcond);  // the LU alone lets it through
  EXPECT_THROW(RpimShapeFunctions(nodes, near_search, 0.01).evaluate(x, true), SingularRpimMatrix);
}

TEST(Lrpim, PatchTestPassesToRoundOffWithTheDivergenceCorrection) {
  const LrpimPatchReport c = run_lrpim_patch_test(5, 1.5, 8, 16, true);
  const LrpimPatchReport p = run_lrpim_patch_test(5, 1.5, 8, 16, false);
  std::cout << "patch test, " << c.num_nodes << " nodes: corrected " << c.max_relative_error << " (nodes "
            << c.nodal_relative_error << ", strain " << c.strain_relative_error << "); plain "
            << p.max_relative_error << " (nodes " << p.nodal_relative_error << ", strain " << p.strain_relative_error
            << "); divergence defect " << c.divergence_defect << "\n";
  EXPECT_LT(c.max_relative_error, 1e-13);     // 4.7e-15
  EXPECT_LT(c.nodal_relative_error, 1e-13);   // 5.1e-15
  EXPECT_LT(c.strain_relative_error, 1e-11);  // 1.7e-13
  EXPECT_EQ(c.newton_iterations, 1);
  // Without it, what is left is the angular quadrature error of the clipped spheres: 5.2e-4 with the Shepard test
  // functions (1.9e-3 with the plain spline; docs/LRPIM.md §4).
  EXPECT_GT(p.max_relative_error, 4e-4);
  EXPECT_LT(p.max_relative_error, 7e-4);
  EXPECT_NEAR(p.divergence_defect, 1.23e-3, 0.02e-3);  // 2.71e-3 with the plain spline
}

TEST(Lrpim, PatchTestPassesOnTheCloudsOwnBoundaryTriangles) {
  // The general body as a load case has it: the box mesh's 2 x 6 x 25 boundary triangles, whose vertices are the
  // surface nodes (jittered inside), each labelled with its face's condition.
  const LrpimPatchReport c = run_lrpim_patch_test(5, 1.5, 8, 16, true, true);
  std::cout << "patch test on the cloud's boundary triangles: " << c.max_relative_error << " (nodes "
            << c.nodal_relative_error << ", strain " << c.strain_relative_error << "), divergence defect "
            << c.divergence_defect << "\n";
  EXPECT_LT(c.max_relative_error, 1e-13);
  EXPECT_LT(c.nodal_relative_error, 1e-13);
  EXPECT_LT(c.strain_relative_error, 1e-11);
  EXPECT_EQ(c.newton_iterations, 1);
}

TEST(Lrpim, CantileverConvergesTowardsTimoshenko) {
  std::vector<double> h, l2, en;
  for (int nd : {2, 3, 4}) {
    const LrpimCantileverReport r = run_lrpim_cantilever(nd);
    std::cout << "cantilever nd " << nd << " (" << r.num_nodes << " nodes): L2 " << r.l2_error << ", energy "
              << r.energy_error << ", tip " << r.tip_deflection / r.exact_tip_deflection << " of exact, "
              << r.seconds << " s\n";
    h.push_back(r.node_spacing);
    l2.push_back(r.l2_error);
    en.push_back(r.energy_error);
  }
  const double rate_l2 = core::convergence_rate(h, l2), rate_en = core::convergence_rate(h, en);
  std::cout << "cantilever rates over 2-4 cells: L2 " << rate_l2 << ", energy " << rate_en << "\n";
  // Measured with the Shepard test functions: L2 0.0223, 0.0029, 0.0048; energy 0.1167, 0.0709, 0.0508 (with the
  // plain spline: L2 0.0708, 0.0339, 0.0291, energy 0.1264, 0.0736, 0.0554; docs/LRPIM.md §4).
  EXPECT_NEAR(l2[0], 0.0223, 0.001);
  EXPECT_NEAR(l2[1], 0.0029, 0.0003);
  EXPECT_NEAR(l2[2], 0.0048, 0.0003);
  EXPECT_NEAR(en[0], 0.1167, 0.003);
  EXPECT_NEAR(en[1], 0.0709, 0.002);
  EXPECT_NEAR(en[2], 0.0508, 0.002);
  // Fitted 2.39 (L2) and 1.20 (energy), against the EFG's 1.96 and 1.42; the L2 error is smallest at 3 cells.
  EXPECT_GT(rate_l2, 2.2);
  EXPECT_GT(rate_en, 1.1);
}

// A free node with no sub-domain inside the body would carry an empty row, which the factorisation reports only as a
// "zero column" of its permuted matrix (how a lost clamp mark showed in CI, when the set-up kept its per-node flags
// as bits that two threads could overwrite). The set-up names the node instead.
// Why the cantilever's energy rate (1.20) falls short of the EFG's (1.42), docs/LRPIM.md §4: the rates over 2, 3 and 4
// cells with one ingredient changed at a time. Disabled: a measurement, not a test (about 3 minutes).
TEST(Lrpim, DISABLED_CantileverRateStudy) {
  struct Variant {
    std::string name;
    std::function<void(LrpimProblem*)> adjust;
    RpimParameters rpim;
    double alpha_q = 1.5;
  };
  RpimParameters thirty, full_shells, broken_shell;
  thirty.num_neighbours = 30;
  full_shells.num_neighbours = 27;  // the node and its 6, 12 and 8 neighbours at h, sqrt(2) h, sqrt(3) h on the grid
  broken_shell.num_neighbours = 23;  // 4 of the 8 at sqrt(3) h: a tie broken arbitrarily, as 20 breaks the 12 at sqrt(2) h
  const char* only = std::getenv("LRPIM_STUDY_ONLY");  // a substring of the variants' names
  std::vector<Variant> variants = {
      {"shipped (8 x 16 x 4, alpha_q 1.5, 20 nodes)", {}, {}, 1.5},
      {"angular rule 16 x 32 x 8", [](LrpimProblem* p) { p->rule.polar = 16, p->rule.azimuthal = 32, p->rule.radial = 8; }, {}, 1.5},
      {"alpha_q 1.0", {}, {}, 1.0},
      {"alpha_q 2.0", {}, {}, 2.0},
      {"30 support nodes", {}, thirty, 1.5},
      {"27 support nodes (complete shells)", {}, full_shells, 1.5},
      {"23 support nodes", {}, broken_shell, 1.5},
      {"spline test function", [](LrpimProblem* p) { p->test_function = LrpimTestFunction::spline; }, {}, 1.5},
  };
  for (const Variant& v : variants) {
    if (only && v.name.find(only) == std::string::npos) continue;
    std::vector<double> h, l2, en;
    std::ostringstream line;
    for (int nd : {2, 3, 4}) {
      const LrpimCantileverReport r = run_lrpim_cantilever(nd, v.rpim, v.alpha_q, v.adjust);
      h.push_back(r.node_spacing), l2.push_back(r.l2_error), en.push_back(r.energy_error);
      line << "  " << nd << " cells: L2 " << r.l2_error << ", energy " << r.energy_error << ", tip "
           << r.tip_deflection / r.exact_tip_deflection << "\n";
    }
    std::cout << v.name << ": rates L2 " << core::convergence_rate(h, l2) << ", energy "
              << core::convergence_rate(h, en) << "\n" << line.str() << std::flush;
  }
}

TEST(Lrpim, NodeWithoutEquationsIsNamedAtSetUp) {
  LrpimProblem p = lrpim_cantilever_problem(2);
  const Eigen::Index n = p.nodes.rows();
  p.nodes.conservativeResize(n + 1, 3);
  p.nodes.row(n) << 0.3, 0.0, 0.0;  // 200 mm beyond the x = L end: its 15 mm sphere misses the beam
  try {
    const LrpimModel model(std::move(p));
    FAIL() << "a node outside the body must be refused";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("node " + std::to_string(n) + " at (300, 0, 0) mm"), std::string::npos) << m;
    EXPECT_NE(m.find("carries no equations"), std::string::npos) << m;
    EXPECT_NE(m.find("Remove the node or mend the surface"), std::string::npos) << m;
  }
  // The same beam without the stray node sets up, with its 9 nodes at x = 0 held.
  EXPECT_EQ(LrpimModel(lrpim_cantilever_problem(2)).statistics().num_constrained_nodes, 9);
}

// A failed Newton solve says whether a smaller step can help: it names the set-up's worst support and the
// divergence defect beside the CI lung's (on the real right lobe, docs/LRPIM.md §6, no step size helped).
TEST(Lrpim, NewtonFailureReportsTheSetUpDiagnostics) {
  LrpimProblem p = lrpim_cantilever_problem(2);
  p.material.k = 2.0;            // nonlinear: the first update from u = 0 is the linear solution, not converged
  p.max_newton_iterations = 1;
  LrpimModel model(std::move(p));
  try {
    model.run();
    FAIL() << "one Newton iteration cannot converge the nonlinear law";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("Newton did not converge at t = "), std::string::npos) << m;
    EXPECT_NE(m.find("rcond " + [&] {
                std::ostringstream r;
                r << model.statistics().min_rcond;
                return r.str();
              }()),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("divergence defect is"), std::string::npos) << m;
    EXPECT_NE(m.find("no step size helps"), std::string::npos) << m;
  }
}

TEST(Lrpim, CreepBarFollowsTheClosedFormAtKZero) {
  const LrpimCreepReport r = run_lrpim_creep_bar(0.0);
  std::cout << "creep bar k = 0: max relative error " << r.max_relative_error << " over " << r.times.size()
            << " steps\n";
  // The linear field is reproduced; what is left is the recursion's time-step error, the EFG's 2.6e-5 at dt = 0.1 s.
  EXPECT_LT(r.max_relative_error, 3e-5);  // 2.6e-5
  EXPECT_NEAR(r.strain.front(), 100.0 / 6000.0, 1e-10 * 100.0 / 6000.0);
}

TEST(Lrpim, CreepBarFollowsTheClosedFormOfTheNonlinearLaw) {
  const double k = 2.0;
  const LrpimCreepReport r = run_lrpim_creep_bar(k);
  std::cout << "creep bar k = 2: max relative error " << r.max_relative_error << "\n";
  EXPECT_LT(r.max_relative_error, 3e-5);  // 2.5e-5
  const double n0 = 100.0 / 6000.0;       // N at t = 0: sigma0 / K1
  EXPECT_NEAR(r.strain.front(), (std::sqrt(1.0 + 4.0 * k * n0) - 1.0) / (2.0 * k), 1e-10 * n0);
  // k != 0 changes the answer: the same load at k = 0 strains more than 1% further.
  EXPECT_GT(n0 - r.strain.front(), 0.01 * n0);
}

TEST(Lrpim, KeptFactorsGiveWayOnTheRunsMeanRateNotOnOneSlowUpdate) {
  using meshless::kept_factors_too_slow;
  const double target = 1e-8;
  // lung_small's step 4 on kept factors (README command 1): 2.8e-2, 1.9e-3, 1.3e-4, 3.0e-6, then 1.6e-6. The last
  // update contracted by 0.53, the run by 0.15 per update: keep the factors (the last-update rule factorised here).
  EXPECT_FALSE(kept_factors_too_slow(1.6e-6, 3.0e-6, 2.8e-2, 4, target, 4, 0.2, 25));
  // A run that stalls: from 1e-2 one update of 0.01, then 0.9 per update. Kept after the first slow update (mean
  // 0.095), refactorised after the second (mean 0.2008).
  EXPECT_FALSE(kept_factors_too_slow(9e-5, 1e-4, 1e-2, 2, target, 2, 0.2, 25));
  EXPECT_TRUE(kept_factors_too_slow(8.1e-5, 9e-5, 1e-2, 3, target, 3, 0.2, 25));
  // An update that did not reduce ||R|| ends the run whatever the mean.
  EXPECT_TRUE(kept_factors_too_slow(2e-6, 1.9e-6, 1e-1, 4, target, 4, 0.2, 25));
  // The guard: 0.15 per update is fast enough, but from 1e-2 at iteration 20 the target needs 7.3 more updates.
  EXPECT_TRUE(kept_factors_too_slow(1e-2 * 0.15, 1e-2, 1e-2, 1, target, 20, 0.2, 25));
  EXPECT_FALSE(kept_factors_too_slow(1e-2 * 0.15, 1e-2, 1e-2, 1, target, 10, 0.2, 25));
  // Nothing measured on these factors in this step yet.
  EXPECT_FALSE(kept_factors_too_slow(5e-2, 1.0, 5e-2, 0, target, 0, 0.2, 25));
}
