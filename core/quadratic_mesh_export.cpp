#include "core/quadratic_mesh_export.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include "core/gmsh_session.hpp"

namespace core {
namespace {

constexpr int kGmshTriangle3 = 2, kGmshTet4 = 4, kGmshTriangle6 = 9, kGmshTet10 = 11, kGmshPoint = 15;

void check_sets(const TetMesh& mesh, const QuadraticExportSets& sets) {
  std::vector<int> owner(static_cast<std::size_t>(mesh.boundary_faces.rows()), -1);
  for (std::size_t s = 0; s < sets.face_sets.size(); ++s) {
    const NamedIndexSet& set = sets.face_sets[s];
    if (set.indices.empty()) throw std::invalid_argument("write_quadratic_mesh: face set " + set.name + " is empty");
    for (const int f : set.indices) {
      if (f < 0 || f >= mesh.boundary_faces.rows())
        throw std::invalid_argument(fmt::format("write_quadratic_mesh: face set {} names face {} of {}", set.name, f,
                                                mesh.boundary_faces.rows()));
      if (owner[static_cast<std::size_t>(f)] >= 0)
        throw std::invalid_argument(fmt::format("write_quadratic_mesh: face {} lies in the sets {} and {}", f,
                                                sets.face_sets[static_cast<std::size_t>(owner[f])].name, set.name));
      owner[static_cast<std::size_t>(f)] = static_cast<int>(s);
    }
  }
  for (const NamedIndexSet& set : sets.cell_sets) {
    if (set.indices.empty()) throw std::invalid_argument("write_quadratic_mesh: cell set " + set.name + " is empty");
    for (const int t : set.indices)
      if (t < 0 || t >= mesh.num_tets())
        throw std::invalid_argument(
            fmt::format("write_quadratic_mesh: cell set {} names tet {} of {}", set.name, t, mesh.num_tets()));
  }
}

/// Gmsh reports a failed write in its log, not always by an exception: check that the file is there.
void write_checked(const std::filesystem::path& file) {
  gmsh::write(file.string());
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error) || std::filesystem::file_size(file, error) == 0 || error)
    throw std::runtime_error(fmt::format("Gmsh could not write {}; check that its folder is writable and the disk "
                                         "has space",
                                         file.string()));
}

}  // namespace

QuadraticTetMesh write_quadratic_mesh(const TetMesh& mesh, const QuadraticExportSets& sets,
                                      const std::filesystem::path& msh_file, const std::filesystem::path& inp_file) {
  check_sets(mesh, sets);
  const std::size_t n_tets = static_cast<std::size_t>(mesh.num_tets());
  const std::size_t n_faces = static_cast<std::size_t>(mesh.boundary_faces.rows());
  GmshSession session;
  gmsh::model::add("tissue_export");

  // A Gmsh element lies in exactly one entity, so the tets are split into one discrete volume per combination of
  // cell sets they belong to; a set's physical group is then the union of the volumes whose combination holds it.
  std::vector<std::vector<int>> membership(n_tets);
  for (std::size_t s = 0; s < sets.cell_sets.size(); ++s)
    for (const int t : sets.cell_sets[s].indices) membership[static_cast<std::size_t>(t)].push_back(static_cast<int>(s));
  std::map<std::vector<int>, std::vector<std::size_t>> tets_of_combination;
  for (std::size_t t = 0; t < n_tets; ++t) {
    std::vector<int>& m = membership[t];
    std::sort(m.begin(), m.end());
    m.erase(std::unique(m.begin(), m.end()), m.end());
    tets_of_combination[m].push_back(t);
  }
  std::vector<int> all_volumes;
  std::vector<std::vector<int>> volumes_of_set(sets.cell_sets.size());
  bool nodes_added = false;
  for (const auto& [combination, tets] : tets_of_combination) {
    const int entity = gmsh::model::addDiscreteEntity(3);
    all_volumes.push_back(entity);
    for (const int s : combination) volumes_of_set[static_cast<std::size_t>(s)].push_back(entity);
    if (!nodes_added) {  // every node on the first volume: Gmsh only needs each node classified once
      std::vector<std::size_t> tags(static_cast<std::size_t>(mesh.num_vertices()));
      std::vector<double> coordinates(3 * tags.size());
      for (std::size_t v = 0; v < tags.size(); ++v) {
        tags[v] = v + 1;
        for (int k = 0; k < 3; ++k) coordinates[3 * v + k] = mesh.vertices(static_cast<Eigen::Index>(v), k);
      }
      gmsh::model::mesh::addNodes(3, entity, tags, coordinates);
      nodes_added = true;
    }
    std::vector<std::size_t> element_tags, node_tags;
    for (const std::size_t t : tets) {
      element_tags.push_back(t + 1);
      for (int k = 0; k < 4; ++k) node_tags.push_back(static_cast<std::size_t>(mesh.tets(static_cast<Eigen::Index>(t), k)) + 1);
    }
    gmsh::model::mesh::addElementsByType(entity, kGmshTet4, element_tags, node_tags);
  }
  std::vector<int> surface_of_set;
  for (const NamedIndexSet& set : sets.face_sets) {
    const int entity = gmsh::model::addDiscreteEntity(2);
    surface_of_set.push_back(entity);
    std::vector<std::size_t> element_tags, node_tags;
    for (const int f : set.indices) {
      element_tags.push_back(n_tets + static_cast<std::size_t>(f) + 1);
      for (int k = 0; k < 3; ++k) node_tags.push_back(static_cast<std::size_t>(mesh.boundary_faces(f, k)) + 1);
    }
    gmsh::model::mesh::addElementsByType(entity, kGmshTriangle3, element_tags, node_tags);
  }
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, all_volumes), sets.body_name);
  for (std::size_t s = 0; s < sets.cell_sets.size(); ++s)
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, volumes_of_set[s]), sets.cell_sets[s].name);
  std::vector<std::pair<int, int>> surface_groups;
  for (std::size_t s = 0; s < sets.face_sets.size(); ++s) {
    const int group = gmsh::model::addPhysicalGroup(2, {surface_of_set[s]});
    gmsh::model::setPhysicalName(2, group, sets.face_sets[s].name);
    surface_groups.emplace_back(2, group);
  }

  // Straight-sided quadratic elements: the midside nodes at the edges' midpoints, shared by the tets and the faces.
  gmsh::option::setNumber("Mesh.SecondOrderLinear", 1);
  gmsh::option::setNumber("Mesh.SecondOrderIncomplete", 0);
  gmsh::model::mesh::setOrder(2);

  QuadraticTetMesh result;
  {
    std::vector<std::size_t> tags;
    std::vector<double> coordinates, parametric;
    gmsh::model::mesh::getNodes(tags, coordinates, parametric, -1, -1, false, false);
    result.nodes.resize(static_cast<Eigen::Index>(tags.size()), 3);
    std::vector<char> seen(tags.size(), 0);
    for (std::size_t i = 0; i < tags.size(); ++i) {
      if (tags[i] < 1 || tags[i] > tags.size() || seen[tags[i] - 1])
        throw std::logic_error("write_quadratic_mesh: Gmsh's second-order node tags are not 1..N");
      seen[tags[i] - 1] = 1;
      for (int k = 0; k < 3; ++k) result.nodes(static_cast<Eigen::Index>(tags[i] - 1), k) = coordinates[3 * i + k];
    }
  }
  // Gmsh renumbers the elements and nodes when it raises the order, but keeps each entity's elements in the order
  // they were added and their corners in order: read them back per entity, and check the corners' positions.
  result.tets.resize(static_cast<Eigen::Index>(n_tets), 10);
  result.tet_elements.assign(n_tets, 0);
  result.faces = NodeTagMatrix6::Zero(static_cast<Eigen::Index>(n_faces), 6);
  std::size_t largest_tag = 0;
  // Gmsh renumbers the nodes too: a TetMesh vertex's node is the one at the same corner of the same element, which
  // must be the same node wherever the vertex is a corner, at the vertex's position.
  result.vertex_nodes.assign(static_cast<std::size_t>(mesh.num_vertices()), 0);
  auto same_corner = [&](int vertex, std::size_t node) {
    std::size_t& known = result.vertex_nodes[static_cast<std::size_t>(vertex)];
    if (known == 0) {
      if (node < 1 || node > static_cast<std::size_t>(result.nodes.rows()) ||
          result.nodes.row(static_cast<Eigen::Index>(node - 1)) != mesh.vertices.row(vertex))
        throw std::logic_error("write_quadratic_mesh: a corner of Gmsh's raised element is not the TetMesh's vertex");
      known = node;
    } else if (known != node) {
      throw std::logic_error("write_quadratic_mesh: Gmsh's raised elements disagree on a vertex's node");
    }
  };
  auto read_back = [&](int dim, int entity, int type, int n_nodes, const std::vector<std::size_t>& indices,
                       auto&& store) {
    std::vector<std::size_t> element_tags, node_tags;  // fresh: Gmsh 4.8 fills non-empty vectors in place
    gmsh::model::mesh::getElementsByType(type, element_tags, node_tags, entity);
    if (element_tags.size() != indices.size())
      throw std::logic_error(fmt::format("write_quadratic_mesh: Gmsh raised {} of the {} elements of entity ({}, {})",
                                         element_tags.size(), indices.size(), dim, entity));
    for (std::size_t e = 0; e < element_tags.size(); ++e) {
      largest_tag = std::max(largest_tag, element_tags[e]);
      store(indices[e], element_tags[e], &node_tags[static_cast<std::size_t>(n_nodes) * e]);
    }
  };
  std::size_t volume = 0;
  for (const auto& [combination, tets] : tets_of_combination)
    read_back(3, all_volumes[volume++], kGmshTet10, 10, tets,
              [&](std::size_t t, std::size_t tag, const std::size_t* nodes) {
                for (int k = 0; k < 10; ++k) result.tets(static_cast<Eigen::Index>(t), k) = nodes[k];
                for (int k = 0; k < 4; ++k) same_corner(mesh.tets(static_cast<Eigen::Index>(t), k), nodes[k]);
                result.tet_elements[t] = tag;
              });
  for (std::size_t s = 0; s < sets.face_sets.size(); ++s) {
    const std::vector<std::size_t> faces(sets.face_sets[s].indices.begin(), sets.face_sets[s].indices.end());
    read_back(2, surface_of_set[s], kGmshTriangle6, 6, faces, [&](std::size_t f, std::size_t, const std::size_t* nodes) {
      for (int k = 0; k < 6; ++k) result.faces(static_cast<Eigen::Index>(f), k) = nodes[k];
      for (int k = 0; k < 3; ++k) same_corner(mesh.boundary_faces(static_cast<Eigen::Index>(f), k), nodes[k]);
    });
  }

  if (!msh_file.empty()) {
    gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
    gmsh::option::setNumber("Mesh.Binary", 0);
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    write_checked(msh_file);
  }
  if (!inp_file.empty()) {
    // The .inp: the faces become node sets (physical points on their nodes), so that only the C3D10 elements are
    // written as elements (header).
    gmsh::model::removePhysicalGroups(surface_groups);
    for (std::size_t s = 0; s < sets.face_sets.size(); ++s) {
      std::set<std::size_t> nodes;
      for (const int f : sets.face_sets[s].indices)
        for (int k = 0; k < 6; ++k) nodes.insert(result.faces(f, k));
      const int entity = gmsh::model::addDiscreteEntity(0);
      std::vector<std::size_t> element_tags, node_tags(nodes.begin(), nodes.end());
      for (std::size_t i = 0; i < node_tags.size(); ++i) element_tags.push_back(++largest_tag);
      gmsh::model::mesh::addElementsByType(entity, kGmshPoint, element_tags, node_tags);
      gmsh::model::setPhysicalName(0, gmsh::model::addPhysicalGroup(0, {entity}), sets.face_sets[s].name);
    }
    gmsh::option::setNumber("Mesh.SaveGroupsOfNodes", 1);
    gmsh::option::setNumber("Mesh.SaveGroupsOfElements", 1);
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    write_checked(inp_file);
  }
  result.next_element_tag = largest_tag + 1;
  return result;
}

}  // namespace core
