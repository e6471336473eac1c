// 3-D cantilever under a parabolic end shear vs Timoshenko & Goodier (nu = 0, elastic limit k = 0, dt = 0):
// the L2 and energy-norm errors must converge over four node spacings. With a linear basis the asymptotic rates
// are 2 (L2) and 1 (energy); over these spacings the energy error still falls faster than that. The bounds
// (meshless/verification/verification_problems.hpp) sit just under the measured rates, so a lost order fails.
#include <gtest/gtest.h>

#include <iostream>
#include <vector>

#include "core/convergence_rate.hpp"
#include "meshless/verification/verification_problems.hpp"

namespace meshless {
namespace {

struct Study {
  std::vector<double> h, l2, energy;
  double rate_l2 = 0.0, rate_energy = 0.0;
};

Study cantilever_study(double d_max, int quadrature_order = 3) {
  Study s;
  for (int nd : {2, 3, 4, 6}) {
    const CantileverReport r = run_cantilever(nd, quadrature_order, true, d_max);
    std::cout << "d_max " << d_max << ", order " << quadrature_order << ", h = " << r.node_spacing * 1e3 << " mm ("
              << r.num_nodes << " nodes): L2 " << r.l2_error << ", energy " << r.energy_error << ", tip "
              << r.tip_deflection << " (exact " << r.exact_tip_deflection << "), " << r.seconds << " s\n";
    s.h.push_back(r.node_spacing);
    s.l2.push_back(r.l2_error);
    s.energy.push_back(r.energy_error);
  }
  s.rate_l2 = core::convergence_rate(s.h, s.l2);
  s.rate_energy = core::convergence_rate(s.h, s.energy);
  std::cout << "rates: L2 " << s.rate_l2 << ", energy " << s.rate_energy << "\n";
  return s;
}

const Study& default_support_study() {
  static const Study s = cantilever_study(2.0);  // the schema's default, core::MeshlessSpec::support_factor
  return s;
}

TEST(EfgCantilever, ConvergesToTimoshenkoSolution) {
  const Study& s = default_support_study();  // measured rates: L2 1.96, energy 1.42
  EXPECT_GE(s.rate_l2, kCantileverMinRateL2);
  EXPECT_GE(s.rate_energy, kCantileverMinRateEnergy);
}

// Why the default support is not the smaller d_max = 1.5, although it couples each node to 0.4x as many and its
// AMG-Krylov solve needs a tenth of the iterations (docs/MESHLESS.md §2, "Support size"): the cantilever does not
// converge at the rate of a linear basis with it, and a finer quadrature (order 5) does not restore the rate, so
// the approximation, not the integration, is at fault. Measured at order 3: rates 0.70 (L2) and 0.36 (energy);
// at h = 3.3 mm the errors are 21x (L2) and 4.7x (energy) those of d_max = 2. At order 5: 0.89 and 0.37.
TEST(EfgCantilever, SmallerSupportLosesTheRate) {
  const Study& wide = default_support_study();
  const Study small = cantilever_study(1.5), small_order5 = cantilever_study(1.5, 5);
  EXPECT_LT(small.rate_l2, 0.8);
  EXPECT_LT(small.rate_energy, 0.45);
  EXPECT_GT(small.l2.back() / wide.l2.back(), 18.0);
  EXPECT_GT(small.energy.back() / wide.energy.back(), 4.2);
  EXPECT_LT(small_order5.rate_l2, 1.0);
  EXPECT_LT(small_order5.rate_energy, 0.45);
}

}  // namespace
}  // namespace meshless
