#include "reference_fem/sample_evaluator.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/fe/fe.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/grid_tools_cache.h>

#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace reference_fem {
namespace {

using namespace dealii;

/// Closest point of the reference tetrahedron to `p` (approximate: clamp the barycentric coordinates to
/// >= 0 and renormalise). Exact for the tiny overshoots of surface points outside a faceted mesh.
Point<3> clamp_to_reference_tet(const Point<3>& p) {
  double lambda[4] = {1.0 - p[0] - p[1] - p[2], p[0], p[1], p[2]};
  double sum = 0.0;
  for (double& l : lambda) {
    l = std::max(l, 0.0);
    sum += l;
  }
  return Point<3>(lambda[1] / sum, lambda[2] / sum, lambda[3] / sum);
}

/// Whether `cell` may hold a point on lip `side` of the cut: no vertex (nor the centroid) lies behind the front on
/// the other side. Vertices on the crack itself (duplicated, one per lip) do not decide.
bool on_lip(const core::RuledSurface& cut, const typename Triangulation<3>::active_cell_iterator& cell, int side) {
  constexpr double kOnCrack = 1e-6;  // [m] Gmsh puts the crack's nodes on its planes to round-off
  auto other_side = [&](const Point<3>& p) {
    const core::CutFrame f = cut.frame(Eigen::Vector3d(p[0], p[1], p[2]));
    return f.behind_front && std::abs(f.s) > kOnCrack && (f.s > 0 ? 1 : -1) != side;
  };
  for (const unsigned int v : cell->vertex_indices())
    if (other_side(cell->vertex(v))) return false;
  return !other_side(cell->center());
}

}  // namespace

SampleEvaluator::SampleEvaluator(const Mapping<3>& mapping, const Triangulation<3>& whole_mesh,
                                 const DoFHandler<3>& dof_handler, const Eigen::MatrixXd& points, double tolerance,
                                 const core::RuledSurface* cut)
    : dof_handler_(dof_handler) {
  const Triangulation<3>& tria = whole_mesh;
  GridTools::Cache<3, 3> cache(tria, mapping);
  typename Triangulation<3>::active_cell_iterator hint;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Point<3> p(points(i, 0), points(i, 1), points(i, 2));
    Location location;
    double offset = 0.0;
    // Next to a crack the point belongs to one lip: the shared rule (core::RuledSurface::side).
    const Eigen::Vector3d x(p[0], p[1], p[2]);
    const bool lip_rule = cut && cut->frame(x).behind_front;
    const int side = lip_rule ? cut->side(x) : 0;
    auto allowed = [&](const typename Triangulation<3>::active_cell_iterator& cell) {
      return !lip_rule || on_lip(*cut, cell, side);
    };
    auto found = GridTools::find_active_cell_around_point(cache, p, hint, {}, 1e-10);
    // deal.II may hand back its best guess even when the point is not in that cell (e.g. next to a crack,
    // where two vertices share a position), so check the reference coordinates ourselves.
    if (found.first != tria.end() && found.first->reference_cell().contains_point(found.second, 1e-8) &&
        allowed(found.first)) {
      location.unit_point = found.second;
      hint = found.first;
    } else {
      // Outside the faceted mesh (or next to a crack, whose duplicated nodes share one position and
      // confuse the vertex-based search): project into each cell around every vertex at the nearest
      // position, keep the closest.
      const auto& vertices = tria.get_vertices();
      const std::vector<bool>& used = tria.get_used_vertices();
      double nearest = std::numeric_limits<double>::max();
      for (unsigned int v = 0; v < vertices.size(); ++v)
        if (used[v]) nearest = std::min(nearest, vertices[v].distance(p));
      std::set<typename Triangulation<3>::active_cell_iterator> candidates;
      for (unsigned int v = 0; v < vertices.size(); ++v)
        if (used[v] && vertices[v].distance(p) <= nearest * (1 + 1e-9) + 1e-14)
          for (const auto& cell : cache.get_vertex_to_cell_map()[v]) candidates.insert(cell);
      // ...and one more ring of cells, for points in a cell that does not touch the nearest vertex.
      std::set<typename Triangulation<3>::active_cell_iterator> ring = candidates;
      for (const auto& cell : ring)
        for (const unsigned int k : cell->vertex_indices())
          for (const auto& neighbour : cache.get_vertex_to_cell_map()[cell->vertex_index(k)])
            candidates.insert(neighbour);
      double best = std::numeric_limits<double>::max();
      for (const auto& cell : candidates) {
        if (!allowed(cell)) continue;
        const Point<3> unit = clamp_to_reference_tet(mapping.transform_real_to_unit_cell(cell, p));
        const double d = mapping.transform_unit_to_real_cell(cell, unit).distance(p);
        if (d < best) {
          best = d;
          found = {cell, unit};
        }
      }
      offset = best;
      location.unit_point = found.second;
      if (offset > tolerance) {
        std::ostringstream msg;
        msg << "SampleEvaluator: point " << i << " lies " << offset * 1e3 << " mm outside the FEM mesh"
            << (lip_rule ? " on its lip of the cut" : "") << " (tolerance " << tolerance * 1e3 << " mm)";
        throw std::runtime_error(msg.str());
      }
    }
    location.cell_id = found.first->id();
    locations_.push_back(location);
    offsets_.push_back(offset);
  }

  // The process that owns a point's cell evaluates it (coarse cells: the meshes are not refined).
  std::map<CellId, typename DoFHandler<3>::active_cell_iterator> owned;
  for (const auto& cell : dof_handler.active_cell_iterators())
    if (cell->is_locally_owned()) owned.emplace(cell->id(), cell);
  for (Location& location : locations_) {
    const auto it = owned.find(location.cell_id);
    if (it != owned.end()) location.cell = it->second;
  }
}

Eigen::MatrixXd SampleEvaluator::evaluate(const TrilinosWrappers::MPI::Vector& solution) const {
  const FiniteElement<3>& fe = dof_handler_.get_fe();
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(locations_.size()), 3);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (std::size_t i = 0; i < locations_.size(); ++i) {
    if (locations_[i].cell.state() != IteratorState::valid) continue;  // owned by another process
    locations_[i].cell->get_dof_indices(dofs);
    for (unsigned int k = 0; k < fe.n_dofs_per_cell(); ++k) {
      const unsigned int c = fe.system_to_component_index(k).first;
      u(static_cast<Eigen::Index>(i), c) += solution(dofs[k]) * fe.shape_value(k, locations_[i].unit_point);
    }
  }
  // Each point has exactly one owner: the sum over the processes gathers the values.
  const MPI_Comm communicator = solution.get_mpi_communicator();
  Utilities::MPI::sum(ArrayView<const double>(u.data(), u.size()), communicator, ArrayView<double>(u.data(), u.size()));
  return u;
}

Eigen::MatrixXd vertex_displacements(const DoFHandler<3>& dof_handler, const TrilinosWrappers::MPI::Vector& solution,
                                     const core::TetMesh& mesh) {
  const FiniteElement<3>& fe = dof_handler.get_fe();
  const MPI_Comm communicator = solution.get_mpi_communicator();
  const int rank = static_cast<int>(Utilities::MPI::this_mpi_process(communicator));
  const Eigen::Index n_vertices = mesh.num_vertices();
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(n_vertices, 3);
  // A vertex shared by several processes is reported by the lowest rank among them.
  std::vector<int> reporter(static_cast<std::size_t>(n_vertices), std::numeric_limits<int>::max());
  std::vector<std::pair<int, Eigen::Vector3d>> values;
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    const auto tet = static_cast<Eigen::Index>(cell->id().get_coarse_cell_id());
    cell->get_dof_indices(dofs);
    for (const unsigned int v : cell->vertex_indices()) {
      // The mesh vertex at this cell vertex: the tet's corner at the same position (the four differ).
      int vertex = -1;
      for (int k = 0; k < 4; ++k) {
        const int candidate = mesh.tets(tet, k);
        if (Point<3>(mesh.vertices(candidate, 0), mesh.vertices(candidate, 1), mesh.vertices(candidate, 2)) ==
            cell->vertex(v))
          vertex = candidate;
      }
      if (vertex < 0) throw std::logic_error("vertex_displacements: the triangulation was not built from this mesh");
      const Point<3> unit = cell->reference_cell().template vertex<3>(v);
      Eigen::Vector3d value = Eigen::Vector3d::Zero();
      for (unsigned int k = 0; k < fe.n_dofs_per_cell(); ++k)
        value(fe.system_to_component_index(k).first) += solution(dofs[k]) * fe.shape_value(k, unit);
      values.emplace_back(vertex, value);
      reporter[static_cast<std::size_t>(vertex)] = rank;
    }
  }
  Utilities::MPI::min(ArrayView<const int>(reporter), communicator, ArrayView<int>(reporter));
  for (const auto& [vertex, value] : values)
    if (reporter[static_cast<std::size_t>(vertex)] == rank) u.row(vertex) = value.transpose();
  Utilities::MPI::sum(ArrayView<const double>(u.data(), u.size()), communicator, ArrayView<double>(u.data(), u.size()));
  return u;
}

}  // namespace reference_fem
