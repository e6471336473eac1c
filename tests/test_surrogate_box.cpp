// The surrogate against the full meshless model at forces it was not trained on (paper §3; docs/SURROGATE.md
// §6): on the box of tests/surrogate_box_case.hpp (405 nodes, lung material with k = 1), trained on 8
// levels per axis, the RMSE over every surface node at two held-out forces (one between trained levels, one
// oblique, which also tests the superposition of the axes) is at most 2 % of the full model's contact-node
// displacement. About 20 s of CPU (26 full solves): label long.
#include <gtest/gtest.h>

#include <iostream>

#include "tests/surrogate_box_case.hpp"
#include "meshless/surrogate/surrogate_builder.hpp"

namespace meshless {
namespace {

TEST(SurrogateBox, HeldOutForcesMatchTheFullModelWithinTwoPercent) {
  SurrogateBuildReport report;
  const SurrogateData d = build_surrogate(
      surrogate_box_problem(), surrogate_box_spec(), {},
      [](const std::string& line) { std::cout << "  " << line << "\n"; }, &report);
  ASSERT_EQ(d.contacts.size(), 1u);
  const ContactFit& fit = d.contacts[0];
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = fit.axis[j];
    std::cout << "axis "
              << "xyz"[j] << ": lambda " << a.force_order << " (CV " << a.contact_cv_rms * 1e3
              << " mm), field lambda " << a.field_order << " (CV " << a.field_order_cv_rms * 1e3
              << " mm), eq. 28 training RMS " << a.training_rms * 1e3 << " mm";
    for (int i = 0; i < 3; ++i)
      std::cout << ", (a,b,c)_"
                << "xyz"[i] << " = (" << a.field[i].tangential_order << "," << a.field[i].normal_order << ","
                << a.field[i].contact_order << ") CV " << a.field[i].cv_rms * 1e3 << " mm";
    std::cout << "\n";
  }
  for (const FitSummary& s : fit.summaries) EXPECT_TRUE(s.usable) << s.what << ": " << s.termination;
  ASSERT_EQ(report.holdouts.size(), 2u);
  for (const HoldoutError& e : report.holdouts) {
    std::cout << "held-out force (" << e.load.force.transpose() << ") N: RMSE " << e.rmse * 1e3
              << " mm = " << 100 * e.relative << " % of the contact-node displacement "
              << e.contact_displacement * 1e3 << " mm; contact-node error " << e.contact_error * 1e3
              << " mm\n";
    // The requirement is 2 %; 0.52 % was measured at both forces (docs/SURROGATE.md §6), so a lost contact
    // term or force order shows here.
    EXPECT_LE(e.relative, 0.0075);
    // Eqs. 25-27 at the contact node: exact along one axis, the superposition of the axes costs 0.2 %
    // obliquely.
    EXPECT_LE(e.contact_error, 0.005 * e.contact_displacement);
  }

  // The same data without the contact terms (c = 0: the paper's polynomial surface alone, in 3-D
  // surface-local coordinates): a low-order polynomial cannot follow the dent under the probe
  // (docs/SURROGATE.md §3).
  SurrogateFitOptions polynomial_only = fit_options(surrogate_box_spec());
  polynomial_only.max_contact_order = 0;
  SurrogateData p = d;
  p.contacts = {fit_contact(surface_nodes(surrogate_box_problem().mesh), report.training_data[0],
                            surrogate_box_spec().max_force, polynomial_only)};
  const std::vector<HoldoutError> without =
      holdout_errors(Surrogate(p), report.holdout_loads, report.holdout_solves);
  for (std::size_t h = 0; h < without.size(); ++h) {
    std::cout << "without contact terms: RMSE " << without[h].rmse * 1e3
              << " mm = " << 100 * without[h].relative << " %\n";
    EXPECT_GT(without[h].relative, 3.0 * report.holdouts[h].relative);
  }
}

/// A contact region on the box's top face (docs/SURROGATE.md §4, §6): 5 trained contacts among the 9 top nodes
/// within 7.5 mm of the centre, and the full model at the 2 untrained nodes, each at the two held-out forces. The
/// goal is 2 % of the contact-node displacement at untrained contacts; on this small box (the smooth profile's
/// 10.4 mm radius reaches its sides) 1.90-2.03 % was measured, and 0.65-0.67 % at the trained contacts, where the
/// region answers each contact's own fit. About 50 s: label long.
TEST(SurrogateBox, AContactRegionAnswersAtUntrainedContactsNearTwoPercent) {
  core::SurrogateSpec spec = surrogate_box_spec();
  spec.contact_region = core::ContactRegionSpec{spec.contact_points.front(), 7.5 * 1e-3, 5, 2, 1};
  spec.patch_profile = core::SurrogateSpec::PatchProfile::smooth;  // the case reader's default with a region
  SurrogateBuildReport report;
  const SurrogateData d = build_surrogate(
      surrogate_box_problem(), spec, {}, [](const std::string& line) { std::cout << "  " << line << "\n"; },
      &report);
  ASSERT_EQ(d.contacts.size(), 5u);
  ASSERT_TRUE(d.region.has_value());
  EXPECT_EQ(report.region.region_nodes, 9);
  int untrained = 0;
  double worst_untrained = 0.0, worst_trained = 0.0;
  for (const HoldoutError& e : report.holdouts) {
    std::cout << (e.trained_contact ? "trained" : "UNTRAINED") << " node " << e.load.contact << ", force ("
              << e.load.force.transpose() << ") N: RMSE " << e.rmse * 1e3 << " mm = " << 100 * e.relative
              << " % of the contact-node displacement " << e.contact_displacement * 1e3
              << " mm; contact-node error " << e.contact_error * 1e3 << " mm\n";
    (e.trained_contact ? worst_trained : worst_untrained) =
        std::max(e.trained_contact ? worst_trained : worst_untrained, e.relative);
    untrained += !e.trained_contact;
  }
  EXPECT_EQ(untrained, 4);
  EXPECT_LE(worst_trained, 0.0075);  // as for one contact (the test above)
  EXPECT_LE(worst_untrained, 0.0225);  // 2.03 % measured: the interpolation between contacts costs 1.4 points
}

}  // namespace
}  // namespace meshless
