// 3-D cantilever under a parabolic end shear vs Timoshenko & Goodier (nu = 0, elastic limit k = 0, dt = 0):
// the L2 and energy-norm errors must converge at rate >= 0.9 over four node spacings.
#include <gtest/gtest.h>

#include <iostream>
#include <vector>

#include "meshless/verification_problems.hpp"

namespace meshless {
namespace {

TEST(EfgCantilever, ConvergesToTimoshenkoSolution) {
  std::vector<double> h, l2, energy;
  for (int nd : {2, 3, 4, 6}) {
    const CantileverReport r = run_cantilever(nd);
    std::cout << "cantilever h = " << r.node_spacing * 1e3 << " mm (" << r.num_nodes << " nodes): L2 " << r.l2_error
              << ", energy " << r.energy_error << ", tip " << r.tip_deflection << " (exact " << r.exact_tip_deflection
              << "), " << r.seconds << " s\n";
    h.push_back(r.node_spacing);
    l2.push_back(r.l2_error);
    energy.push_back(r.energy_error);
  }
  const double rate_l2 = convergence_rate(h, l2), rate_energy = convergence_rate(h, energy);
  std::cout << "rates: L2 " << rate_l2 << ", energy " << rate_energy << "\n";
  EXPECT_GE(rate_l2, 0.9);
  EXPECT_GE(rate_energy, 0.9);
  EXPECT_LT(l2.back(), l2.front());
  EXPECT_LT(energy.back(), energy.front());
}

}  // namespace
}  // namespace meshless
