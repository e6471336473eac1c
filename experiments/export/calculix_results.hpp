#pragma once
// Nodal displacements read from a CalculiX .dat file (the tables *NODE PRINT ... U writes), and their evaluation at
// the samples of an exported mesh (`tissue import-ccx`).
//
// The .dat states a table per printed set and time:
//     displacements (vx,vy,vz) for set SAMPLE_CELLS and time  0.1000000E+01
//     <blank line>
//              12  1.234567E-03 -2.345678E-04  0.000000E+00
// Only the tables of the last time are kept (a later step or increment supersedes the earlier ones); tables of
// several sets at that time are merged. CalculiX prints 7 significant digits, a relative resolution of 1e-6.
// Thread safety: pure functions.
#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <map>

namespace experiments {

struct CalculixDisplacements {
  std::map<std::size_t, Eigen::Vector3d> by_node;  ///< node number -> displacement, in the deck's units
  double time = 0.0;                               ///< the time of the tables read
};

/// Read the last displacement tables of `dat_file`. Throws std::runtime_error naming the file when it cannot be
/// read, holds no displacement table (the deck needs *NODE PRINT with U), or a row is malformed (with its line).
CalculixDisplacements read_calculix_dat_displacements(const std::filesystem::path& dat_file);

}  // namespace experiments
