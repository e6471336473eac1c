#pragma once
// The surrogate's small verification case, shared by tests/test_surrogate*.cpp and
// benchmarks/bench_surrogate.cpp: a 40 x 40 x 20 mm block of the shipped cases' lung material (K1 6 kPa, K2
// 12 kPa, eta 18 kPa s, nu 0.4, k = 1) clamped (penalty) on its base, 5 mm nodes (9 x 9 x 5 = 405, 258 on the
// surface), d_max 2, k 6, quadrature order 2; the force ramps over 1 s in two steps. The contact is the
// centre of the top face, the patch radius 6 mm, and each force component is trained over [-0.05, 0.05] N
// (0.44 kPa on the patch: a few per cent strain).
#include "core/case.hpp"
#include "meshless/efg/efg_problem.hpp"

namespace meshless {

EfgProblem surrogate_box_problem();
core::SurrogateSpec surrogate_box_spec();

}  // namespace meshless
