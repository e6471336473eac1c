// The cut as one global frame (core/ruled_surface.hpp): eqs. 29-31 for a straight panel, continuity around kinks and
// beyond the ends, gradients, the side rule both models share, and the input checks.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "core/ruled_surface.hpp"

namespace core {
namespace {

// A kinked incision on the plane z = 0.1, cut downward 30 mm: three panels, turns of about 35 and 50 degrees.
RuledSurface kinked_cut() {
  return RuledSurface({Eigen::Vector3d(0.02, 0.05, 0.1), Eigen::Vector3d(0.045, 0.035, 0.1),
                       Eigen::Vector3d(0.07, 0.045, 0.1), Eigen::Vector3d(0.085, 0.07, 0.1)},
                      -Eigen::Vector3d::UnitZ(), 0.03);
}

std::vector<Eigen::Vector3d> random_points(int n, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-0.02, 0.12);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < n; ++i) p.emplace_back(u(gen), u(gen), u(gen));
  return p;
}

TEST(CutFrame, StraightPanelIsThePapersEquations29To31) {
  // One panel along x from x = 0.01 to 0.05 at y = 0.02, top z = 0.1, depth 0.04 down: zeta = x - 0.01, s = y - 0.02
  // (normal = x-axis x (-z) = +y), and below the bottom the depth overshoot joins eq. 30's d_s.
  const RuledSurface cut({Eigen::Vector3d(0.01, 0.02, 0.1), Eigen::Vector3d(0.05, 0.02, 0.1)}, -Eigen::Vector3d::UnitZ(),
                         0.04, 0.0);
  for (const Eigen::Vector3d& x : random_points(500, 3)) {
    const CutFrame f = cut.frame(x);
    const double zeta = x.x() - 0.01, s = x.y() - 0.02, zeta1 = 0.0, zeta2 = 0.04;
    const double ds = std::abs(zeta - 0.5 * (zeta1 + zeta2)) - std::abs(0.5 * (zeta1 - zeta2));  // eq. 30
    const double below = std::max(0.0, (0.1 - x.z()) - 0.04);
    const double d2 = std::sqrt(std::pow(0.5 * (ds + std::abs(ds)), 2) + s * s + below * below);  // eq. 29 (+ depth)
    EXPECT_NEAR(f.s, s, 1e-15);
    EXPECT_NEAR(f.distance, d2, 1e-15);
    EXPECT_EQ(f.behind_front, ds <= 0.0 && below == 0.0);
    EXPECT_NEAR(f.depth, 0.1 - x.z(), 1e-15);
    // eq. 31: phi = d d_2 / ds = s / d_2, here from the frame's own numbers.
    if (d2 > 0) EXPECT_NEAR(f.s / f.distance, s / d2, 1e-13);  // Measured 2.2e-16
  }
}

TEST(CutFrame, SignedDistanceAndDistanceAreContinuousAroundKinksAndBeyondTheEnds) {
  const RuledSurface cut = kinked_cut();
  std::mt19937 gen(11);
  std::normal_distribution<double> step(0.0, 2e-4);
  double worst_s = 0.0, worst_d = 0.0, worst_phi_off_slab = 0.0;
  for (const Eigen::Vector3d& x : random_points(20000, 5)) {
    const Eigen::Vector3d y = x + Eigen::Vector3d(step(gen), step(gen), step(gen));
    const CutFrame a = cut.frame(x), b = cut.frame(y);
    const double h = (y - x).norm();
    // Both are distance functions (1-Lipschitz): no jump anywhere, also where the closest panel changes.
    worst_s = std::max(worst_s, std::abs(a.s - b.s) / h);
    worst_d = std::max(worst_d, std::abs(a.distance - b.distance) / h);
    // phi = s / d is continuous off the cut: for a pair that stays at least 1 mm from the cut and whose segment
    // does not cross it, |d phi| <= |ds|/d + |s||dd|/d^2 <= 2 h / d.
    if (a.distance > 1e-3 && b.distance > 1e-3 && !cut.segment_crosses(x, y))
      worst_phi_off_slab = std::max(worst_phi_off_slab, std::abs(a.s / a.distance - b.s / b.distance) /
                                                            (2.0 * h / std::min(a.distance, b.distance)));
  }
  std::cout << "max |ds|/|dx| " << worst_s << ", max |dd|/|dx| " << worst_d << ", max |d phi| / (2|dx|/d) "
            << worst_phi_off_slab << "\n";
  EXPECT_LE(worst_s, 1.0 + 1e-9);
  EXPECT_LE(worst_d, 1.0 + 1e-9);
  EXPECT_LE(worst_phi_off_slab, 1.0 + 1e-6);
}

TEST(CutFrame, GradientsMatchFiniteDifferencesWhereSmooth) {
  const RuledSurface cut = kinked_cut();
  const double h = 1e-7;
  int checked = 0;
  double worst = 0.0;
  for (const Eigen::Vector3d& x : random_points(3000, 7)) {
    const CutFrame f = cut.frame(x);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
      const CutFrame p = cut.frame(x + e), m = cut.frame(x - e);
      // Skip the measure-zero sets where a distance has a kink (forward and backward differences disagree).
      const double fs = (p.s - f.s) / h, bs = (f.s - m.s) / h, fd = (p.distance - f.distance) / h,
                   bd = (f.distance - m.distance) / h;
      if (std::abs(fs - bs) > 1e-5 || std::abs(fd - bd) > 1e-5) continue;
      worst = std::max({worst, std::abs(0.5 * (fs + bs) - f.grad_s[k]), std::abs(0.5 * (fd + bd) - f.grad_distance[k])});
      ++checked;
    }
  }
  std::cout << "gradients checked in " << checked << " directions, worst error " << worst << "\n";
  EXPECT_GT(checked, 8000);
  EXPECT_LT(worst, 5e-8);  // Measured 1.42e-10 (round-off of the differences)
}

TEST(CutFrame, SideRuleAndBehindTheFront) {
  const RuledSurface cut = kinked_cut();
  for (int j = 0; j < cut.num_panels(); ++j) {
    const CutPanel p = cut.panel(j);
    const Eigen::Vector3d mid = p.origin + 0.5 * p.length * p.tangent + (0.1 - 0.015) * Eigen::Vector3d::UnitZ();
    EXPECT_EQ(cut.side(mid + 1e-4 * p.normal), 1);
    EXPECT_EQ(cut.side(mid - 1e-4 * p.normal), -1);
    EXPECT_EQ(cut.side(mid), 1);  // on the cut: the s > 0 side
    EXPECT_TRUE(cut.frame(mid + 1e-4 * p.normal).behind_front);
    EXPECT_NEAR(cut.frame(mid).distance, 0.0, 1e-15);
    // 5 mm below the bottom edge: past the front, at 5 mm from it.
    const Eigen::Vector3d below = mid - 0.02 * Eigen::Vector3d::UnitZ();
    EXPECT_FALSE(cut.frame(below).behind_front);
    EXPECT_NEAR(cut.frame(below).distance, 0.005, 1e-15);  // Measured 4.3e-18
    EXPECT_NEAR(cut.front_distance(below), 0.005, 1e-15);  // Measured 4.3e-18
  }
  // The segment test: across a panel in the slab it crosses, below the front it does not.
  const CutPanel p = cut.panel(1);
  const Eigen::Vector3d mid = p.origin + 0.5 * p.length * p.tangent + 0.09 * Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(cut.segment_crosses(mid - 1e-3 * p.normal, mid + 1e-3 * p.normal));
  EXPECT_FALSE(cut.segment_crosses(mid - 1e-3 * p.normal - 0.03 * Eigen::Vector3d::UnitZ(),
                                   mid + 1e-3 * p.normal - 0.03 * Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(cut.segment_crosses(mid + 1e-3 * p.normal, mid + 2e-3 * p.normal));
}

TEST(CutFrame, TruncatedCutIsTheSameSurface) {
  const RuledSurface cut = kinked_cut();
  const RuledSurface half = cut.truncated(0.5 * cut.trace_length());
  EXPECT_NEAR(half.trace_length(), 0.5 * cut.trace_length(), 1e-15);
  EXPECT_EQ(half.num_panels(), 2);
  // Points on the first half of the cut lie on both; the kept part of panel 1 has the same plane.
  EXPECT_NEAR((half.panel_normal(1) - cut.panel_normal(1)).norm(), 0.0, 1e-15);
  for (double a : {0.1, 0.3, 0.45}) {
    const double zeta = a * cut.trace_length();
    // the point of the full cut's top line at arc length zeta, 10 mm down
    Eigen::Vector3d x;
    double left = zeta;
    for (int j = 0; j < cut.num_panels(); ++j) {
      const CutPanel p = cut.panel(j);
      if (left <= p.length) {
        x = cut.top()[j] + left / p.length * (cut.top()[j + 1] - cut.top()[j]) - 0.01 * Eigen::Vector3d::UnitZ();
        break;
      }
      left -= p.length;
    }
    // Measured 0 (exact); 1e-14 leaves ~500x the round-off of 0.1 m coordinates.
    EXPECT_LT(half.distance(x), 1e-14);
    EXPECT_LT(cut.distance(x), 1e-14);
  }
  EXPECT_THROW(cut.truncated(0.0), std::invalid_argument);
  EXPECT_THROW(cut.truncated(2.0 * cut.trace_length()), std::invalid_argument);
}

TEST(CutFrame, BadIncisionsAreRejectedWithTheReason) {
  const Eigen::Vector3d down = -Eigen::Vector3d::UnitZ();
  auto message = [&](std::vector<Eigen::Vector3d> points, double depth) {
    try {
      RuledSurface(std::move(points), down, depth);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // A Z that crosses itself seen from above.
  EXPECT_NE(message({{0, 0, 0}, {0.02, 0.02, 0}, {0.02, 0, 0}, {0, 0.02, 0}}, 0.01).find("crosses itself"),
            std::string::npos);
  // Back and forth along one line.
  EXPECT_NE(message({{0, 0, 0}, {0.02, 0, 0}, {0.01, 0.0001, 0}}, 0.01).find("turns back"), std::string::npos);
  // Two points above each other: no length in the trace.
  EXPECT_NE(message({{0, 0, 0}, {0, 0, -0.01}}, 0.01).find("zero-length"), std::string::npos);
  EXPECT_NE(message({{0, 0, 0}, {0.02, 0, 0}}, 0.0).find("depth"), std::string::npos);
  // A spiral whose last segment runs back across the extension of its first.
  EXPECT_NE(message({{0, 0, 0}, {0.02, 0, 0}, {0.02, 0.02, 0}, {-0.01, 0.02, 0}, {-0.01, -0.01, 0}}, 0.01)
                .find("curls back"),
            std::string::npos);
  EXPECT_EQ(message({{0, 0, 0}, {0.02, 0, 0}, {0.03, 0.01, 0}}, 0.01), "");
}

}  // namespace
}  // namespace core
