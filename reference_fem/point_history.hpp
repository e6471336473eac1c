#pragma once
// History at one quadrature point (step-18 style): the converged Kelvin state at t_n. The recursion of
// eqs. 11–13 needs nothing else, so each step costs O(1) per point whatever the history length.
#include "core/kelvin_law.hpp"

namespace reference_fem {

struct PointHistory {
  core::KelvinState state;  ///< strain, N(strain), viscous stress h_n and stress at t_n
};

}  // namespace reference_fem
