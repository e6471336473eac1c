// The elastic support's stiffness k_s(x) (core::FixedRegionSpec::support_stiffness, docs/MATERIAL.md §3.3): zero
// outside the region, the stated k_s deeper than the taper band, and within the band the C1 smoothstep
// S(s) = s²(3 − 2s) of the depth, so that the traction −k_s u has neither a jump nor a kink at the region's edge.
// Both models call this one definition, so its values here are what both solve.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>

#include "core/case.hpp"

namespace {

/// The shipped lung cases' support: 1.0e6 Pa/m, a 10 mm band, here in a ball of 30 mm about the origin.
core::FixedRegionSpec shipped_like_support() {
  core::FixedRegionSpec s;
  s.kind = core::FixedRegionSpec::Kind::near_point;
  s.distance = 0.030;
  s.support = core::FixedRegionSpec::Support::elastic;
  s.stiffness = 1.0e6;
  s.taper = 0.010;
  return s;
}

/// The point at `depth` [m] inside the ball's edge, along x.
Eigen::Vector3d at_depth(const core::FixedRegionSpec& s, double depth) { return {s.distance - depth, 0.0, 0.0}; }

}  // namespace

TEST(SupportStiffness, IsTheSmoothstepOfTheDepthWithinTheBandAndTheStatedStiffnessBeyondIt) {
  const core::FixedRegionSpec s = shipped_like_support();
  EXPECT_EQ(s.support_stiffness(at_depth(s, -0.001)), 0.0);  // outside the region
  EXPECT_EQ(s.support_stiffness(at_depth(s, 0.0)), 0.0);     // on its edge
  // s = 1/4, 1/2, 3/4: S = 5/32, 1/2, 27/32
  EXPECT_NEAR(s.support_stiffness(at_depth(s, 0.0025)), 1.0e6 * 5.0 / 32.0, 1e-6);
  EXPECT_NEAR(s.support_stiffness(at_depth(s, 0.005)), 0.5e6, 1e-6);
  EXPECT_NEAR(s.support_stiffness(at_depth(s, 0.0075)), 1.0e6 * 27.0 / 32.0, 1e-6);
  EXPECT_NEAR(s.support_stiffness(at_depth(s, 0.010)), 1.0e6, 1e-6);  // the band's inner end
  EXPECT_EQ(s.support_stiffness(at_depth(s, 0.020)), 1.0e6);
  EXPECT_EQ(s.support_stiffness(s.point), 1.0e6);            // the region's centre
}

TEST(SupportStiffness, HasNoKinkAtEitherEndOfTheBand) {
  // The one-sided slopes at the edge and at the band's inner end vanish like the step h: S'(0) = S'(1) = 0, while
  // the mean slope over the band is k_s / b = 1e8 Pa/m².
  const core::FixedRegionSpec s = shipped_like_support();
  const double h = 1e-6;  // [m]
  const double at_edge = (s.support_stiffness(at_depth(s, h)) - s.support_stiffness(at_depth(s, 0.0))) / h;
  const double at_inner_end =
      (s.support_stiffness(at_depth(s, s.taper)) - s.support_stiffness(at_depth(s, s.taper - h))) / h;
  const double mean_slope = s.stiffness / s.taper;
  EXPECT_LT(std::abs(at_edge), 4e-4 * mean_slope);  // 3 h / b = 3e-4 of it
  EXPECT_LT(std::abs(at_inner_end), 4e-4 * mean_slope);
  const double at_middle =
      (s.support_stiffness(at_depth(s, 0.005 + h)) - s.support_stiffness(at_depth(s, 0.005 - h))) / (2 * h);
  EXPECT_NEAR(at_middle, 1.5 * mean_slope, 1e-6 * mean_slope);  // S'(1/2) = 3/2
}

TEST(SupportStiffness, WithoutABandIsUniformAndANearPlaneRegionMeasuresDepthAlongItsNormal) {
  core::FixedRegionSpec s = shipped_like_support();
  s.taper = 0.0;
  EXPECT_EQ(s.support_stiffness(at_depth(s, 1e-9)), 1.0e6);
  EXPECT_EQ(s.support_stiffness(at_depth(s, -1e-9)), 0.0);

  core::FixedRegionSpec slab = shipped_like_support();  // |z| < 30 mm, the band the outer 10 mm of it
  slab.kind = core::FixedRegionSpec::Kind::near_plane;
  slab.normal = Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(slab.support_stiffness({0.5, -0.7, 0.025}), 0.5e6, 1e-6);   // 5 mm deep, anywhere in x and y
  EXPECT_NEAR(slab.support_stiffness({0.0, 0.0, -0.025}), 0.5e6, 1e-6);  // both sides of the plane
  EXPECT_EQ(slab.support_stiffness({0.0, 0.0, 0.031}), 0.0);
}
