#include "experiments/export/calculix_deck.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "core/load_program.hpp"

namespace experiments {
namespace {

/// Gauss-Legendre, 6 points on [0, 1] (nodes, weights): exact to degree 11.
constexpr std::array<std::pair<double, double>, 6> kGauss6 = {{{0.5 * (1 - 0.9324695142031521), 0.5 * 0.1713244923791704},
                                                               {0.5 * (1 - 0.6612093864662645), 0.5 * 0.3607615730481386},
                                                               {0.5 * (1 - 0.2386191860831969), 0.5 * 0.4679139345726910},
                                                               {0.5 * (1 + 0.2386191860831969), 0.5 * 0.4679139345726910},
                                                               {0.5 * (1 + 0.6612093864662645), 0.5 * 0.3607615730481386},
                                                               {0.5 * (1 + 0.9324695142031521), 0.5 * 0.1713244923791704}}};

/// Shape functions of the straight 6-node triangle at (u, v) of the reference triangle: corners 0-2, then the
/// midside nodes of edges 01, 12, 20 (Gmsh's and CalculiX's order).
Eigen::Matrix<double, 6, 1> triangle6_shape(double u, double v) {
  const double l0 = 1.0 - u - v, l1 = u, l2 = v;
  Eigen::Matrix<double, 6, 1> n;
  n << l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0;
  return n;
}

/// ∫ k_s N_i N_j dA over one straight quadratic triangle (corners a, b, c [m]), by the conical product of two
/// 6-point Gauss rules (u = s, v = t (1 - s), dA = 2 A (1 - s) ds dt).
Eigen::Matrix<double, 6, 6> robin_face_matrix(const core::FixedRegionSpec& region, const Eigen::Vector3d& a,
                                              const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double twice_area = (b - a).cross(c - a).norm();
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  for (const auto& [s, ws] : kGauss6)
    for (const auto& [t, wt] : kGauss6) {
      const double u = s, v = t * (1.0 - s);
      const Eigen::Vector3d x = a + u * (b - a) + v * (c - a);
      const double weight = ws * wt * (1.0 - s) * twice_area * region.support_stiffness(x);
      if (weight == 0.0) continue;
      const Eigen::Matrix<double, 6, 1> n = triangle6_shape(u, v);
      m += weight * n * n.transpose();
    }
  return m;
}

/// CalculiX reads a number from at most 20 characters: 14 significant digits fit with sign and exponent.
std::string number(double x) { return fmt::format("{:.14g}", x); }

}  // namespace

CalculixDeck calculix_deck(const core::Case& c, const core::TetMesh& mesh, const core::QuadraticTetMesh& quadratic,
                           const std::string& mesh_file, const CalculixSetNames& names) {
  CalculixDeck deck;
  const core::LoadProgram program = core::load_program(c, mesh);  // the traction both our models apply
  deck.traction = program.traction;
  deck.load_patch_area = program.patch_area;
  deck.long_time_modulus = c.material.equilibrium_modulus();

  std::string& out = deck.text;
  out += "** CalculiX deck written by `tissue export` (docs/FEM_REFERENCE.md, \"An independent FE code: CalculiX\").\n";
  out += fmt::format("** Case {}: the FEM reference's problem at its linear long-time limit (k = 0, E = E_inf).\n",
                     c.name);
  out += "** Units: m, N, Pa. Node and element numbers are those of " + mesh_file + ".\n";
  // No *HEADING here: the mesh file Gmsh wrote has one, and CalculiX refuses a second.
  out += "*INCLUDE, INPUT=" + mesh_file + "\n";
  out += fmt::format("** E_inf = K1 K2 / (K1 + K2) with K1 = {} Pa, K2 = {} Pa; the case's k = {} is not exported.\n",
                     number(c.material.K1), number(c.material.K2), number(c.material.k));
  out += "*MATERIAL, NAME=TISSUE_LONG_TIME\n*ELASTIC\n" + number(deck.long_time_modulus) + ", " +
         number(c.material.nu) + "\n";
  out += "*SOLID SECTION, ELSET=" + names.body + ", MATERIAL=TISSUE_LONG_TIME\n";

  if (c.fixed_region.support == core::FixedRegionSpec::Support::clamp) {
    out += "** The fixed region is clamped: u = 0 on every node of its faces.\n";
    out += "*BOUNDARY\n" + names.support + ", 1, 3\n";
  } else {
    // The Robin matrix, assembled over the fixed faces in node tags.
    std::map<std::pair<std::size_t, std::size_t>, double> off_diagonal;  // (i < j) -> K_ij
    std::map<std::size_t, double> row_sum;
    for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
      if (mesh.face_tags[static_cast<std::size_t>(f)] != core::FaceTag::fixed) continue;
      const Eigen::Matrix<double, 6, 6> m =
          robin_face_matrix(c.fixed_region, mesh.vertices.row(mesh.boundary_faces(f, 0)).transpose(),
                            mesh.vertices.row(mesh.boundary_faces(f, 1)).transpose(),
                            mesh.vertices.row(mesh.boundary_faces(f, 2)).transpose());
      for (int i = 0; i < 6; ++i) {
        const std::size_t ni = quadratic.faces(f, i);
        row_sum[ni] += m.row(i).sum();
        deck.support_stiffness_integral += m.row(i).sum();
        for (int j = 0; j < 6; ++j) {
          const std::size_t nj = quadratic.faces(f, j);
          if (ni < nj) off_diagonal[{ni, nj}] += m(i, j);
        }
      }
    }
    // Entries below round-off of the largest are left out: they are zeros of the uniform-k_s matrix (a corner and
    // the midside node of an adjacent edge; the corners' row sums) that the quadrature leaves at 1e-20.
    double largest = 0.0;
    for (const auto& [nodes, k] : row_sum) largest = std::max(largest, std::abs(k));
    for (const auto& [nodes, k] : off_diagonal) largest = std::max(largest, std::abs(k));
    const double negligible = 1e-13 * largest;
    out += fmt::format(
        "** The fixed region is an elastic support, t = -k_s(x) u with k_s = {} Pa/m tapered over {} m inside its edge:\n"
        "** the consistent matrix K_ij = int k_s N_i N_j dA over its faces, in each direction, as SPRING2 elements of\n"
        "** stiffness -K_ij between node pairs and grounded SPRING1 elements of the row sums (entries below {:.3g} N/m\n"
        "** left out). int k_s dA = {} N/m.\n",
        number(c.fixed_region.stiffness), number(c.fixed_region.taper), negligible,
        number(deck.support_stiffness_integral));
    std::size_t element = quadratic.next_element_tag;
    for (int direction = 1; direction <= 3; ++direction) {
      for (const auto& [nodes, k] : off_diagonal) {
        if (std::abs(k) <= negligible) continue;
        const std::string set = fmt::format("SUPPORT_PAIR_{}", element);
        out += fmt::format("*ELEMENT, TYPE=SPRING2, ELSET={}\n{}, {}, {}\n*SPRING, ELSET={}\n{}, {}\n{}\n", set,
                           element, nodes.first, nodes.second, set, direction, direction, number(-k));
        ++element;
        ++deck.pair_springs;
      }
      for (const auto& [node, k] : row_sum) {
        if (std::abs(k) <= negligible) continue;
        const std::string set = fmt::format("SUPPORT_GROUND_{}", element);
        out += fmt::format("*ELEMENT, TYPE=SPRING1, ELSET={}\n{}, {}\n*SPRING, ELSET={}\n{}\n{}\n", set, element,
                           node, set, direction, number(k));
        ++element;
        ++deck.grounded_springs;
      }
    }
  }

  // The load: each midside node of a load face carries a third of the face's force (the corners none).
  std::map<std::size_t, Eigen::Vector3d> nodal_force;
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    if (mesh.face_tags[static_cast<std::size_t>(f)] != core::FaceTag::load) continue;
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1)).transpose();
    const Eigen::Vector3d cc = mesh.vertices.row(mesh.boundary_faces(f, 2)).transpose();
    const Eigen::Vector3d face_force = program.traction * 0.5 * (b - a).cross(cc - a).norm();
    for (int k = 3; k < 6; ++k) {
      auto [it, inserted] = nodal_force.try_emplace(quadratic.faces(f, k), Eigen::Vector3d::Zero());
      it->second += face_force / 3.0;
    }
  }
  out += "*STEP\n*STATIC\n";
  out += fmt::format("** The load: {} N as the uniform traction ({}, {}, {}) Pa on the {} m^2 load patch, as consistent "
                     "nodal forces.\n",
                     fmt::format("({}, {}, {})", number(c.load.force.x()), number(c.load.force.y()),
                                 number(c.load.force.z())),
                     number(program.traction.x()), number(program.traction.y()), number(program.traction.z()),
                     number(program.patch_area));
  out += "*CLOAD\n";
  for (const auto& [node, force] : nodal_force) {
    for (int d = 0; d < 3; ++d)
      if (force(d) != 0.0) out += fmt::format("{}, {}, {}\n", node, d + 1, number(force(d)));
    deck.total_load += force;
  }
  deck.load_nodes = static_cast<int>(nodal_force.size());
  out += "*NODE PRINT, NSET=" + names.sample_nodes + "\nU\n";
  out += "*NODE FILE\nU\n";
  out += "*END STEP\n";
  return deck;
}

}  // namespace experiments
