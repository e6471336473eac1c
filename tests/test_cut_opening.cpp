// A block with a crack under an opening (mode I) load (experiments/studies/crack_opening.hpp): the meshless model's crack
// (enrichment and visibility, paper §4) against the FEM reference's duplicated-node crack. The cut is the same object
// for both (core::RuledSurface); the opening u_y(+) - u_y(-) along the crack is compared with the FEM's peak.
#include <gtest/gtest.h>

#include <iostream>
#include <map>

#include "core/case.hpp"
#include "experiments/studies/crack_opening.hpp"

namespace experiments {
namespace {

TEST(CutOpening, MeshlessCrackOpensLikeTheFemCrack) {
  std::size_t dofs = 0;
  const std::vector<double> fem = fem_crack_opening(0.0015, &dofs);
  const std::vector<Eigen::Vector3d> profile = crack_opening_profile();
  std::map<meshless::CutTreatment, double> difference;
  for (meshless::CutTreatment treatment : {meshless::CutTreatment::enrichment, meshless::CutTreatment::visibility}) {
    // 1.5 mm cloud, the case schema's default front transition (0: the paper's function).
    const double spacing = 0.0015;
    int nodes = 0;
    const std::vector<double> efg =
        efg_crack_opening(treatment, spacing, spacing * core::MeshlessSpec::kFrontTransitionPerSpacing, &nodes);
    std::cout << "opening [um] along the crack, FEM (" << dofs << " DOFs) vs EFG " << to_string(treatment) << " ("
              << nodes << " nodes):\n";
    for (std::size_t k = 0; k < fem.size(); ++k) {
      std::cout << "  (" << profile[k].transpose() * 1e3 << ") mm: " << fem[k] * 1e6 << " vs " << efg[k] * 1e6 << "\n";
      EXPECT_GT(efg[k], 0.0) << "the lips separate";
    }
    difference[treatment] = largest_difference_of_peak(efg, fem);
    std::cout << to_string(treatment) << ": largest difference " << 100 * difference[treatment]
              << " % of the FEM's peak opening\n";
  }
  // The proposed model matches the FEM crack within 5 % of the peak opening (measured: 2.0 %). The visibility
  // baseline does not close the crack at its front and its shadow lines extend it, so it opens too far near the
  // front (measured: 29 % of the peak, and not converging with the node spacing).
  EXPECT_LT(difference[meshless::CutTreatment::enrichment], 0.05);
  EXPECT_GT(difference[meshless::CutTreatment::visibility], 0.2);
  EXPECT_LT(difference[meshless::CutTreatment::visibility], 0.4);
}

}  // namespace
}  // namespace experiments
