#include "core/crack_embedding.hpp"

#include <gmsh.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>

#include "core/gmsh_mesh.hpp"
#include "core/gmsh_size_fields.hpp"
#include "core/gmsh_session.hpp"

namespace core {
namespace {

constexpr int kCrackGroup = 9001;
constexpr int kOpenBoundaryGroup = 9002;

gmsh::vectorpair boundary_of(const gmsh::vectorpair& entities, bool combined) {
  gmsh::vectorpair out;
  gmsh::model::getBoundary(entities, out, combined, false, false);
  for (auto& e : out) e.second = std::abs(e.second);
  return out;
}

}  // namespace

CrackEmbedding embed_cut_in_body(const std::vector<int>& volume_tags, const RuledSurface& cut, double to_m) {
  namespace occ = gmsh::model::occ;
  // One planar quad per panel (top segment swept along the depth direction), sharing the vertical
  // edges so the cut surface is conforming across the polyline's kinks. Loops run top_i -> top_{i+1}
  // -> bottom_{i+1} -> bottom_i on every panel, so all panels (and their mesh triangles) share one
  // orientation: the Crack plugin averages their normals at shared nodes.
  const Eigen::Vector3d d = cut.direction();
  const double extend = cut.extension();
  std::vector<int> top, bottom, vertical;
  for (const Eigen::Vector3d& p : cut.top()) {
    const Eigen::Vector3d a = (p - extend * d) / to_m, b = (p + cut.depth() * d) / to_m;
    top.push_back(occ::addPoint(a.x(), a.y(), a.z()));
    bottom.push_back(occ::addPoint(b.x(), b.y(), b.z()));
    vertical.push_back(occ::addLine(top.back(), bottom.back()));
  }
  gmsh::vectorpair tools;
  for (int i = 0; i < cut.num_panels(); ++i) {
    const int upper = occ::addLine(top[i], top[i + 1]);
    const int lower = occ::addLine(bottom[i + 1], bottom[i]);
    const int loop = occ::addCurveLoop({upper, vertical[i + 1], lower, -vertical[i]});
    tools.emplace_back(2, occ::addPlaneSurface({loop}));
  }
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::vectorpair body;
  for (int v : volume_tags) body.emplace_back(3, v);
  occ::fragment(body, tools, out, out_map);
  occ::synchronize();

  // Keep the pieces below the surface line (inside the body); the extension above it is deleted.
  // out_map lists the objects (the body volumes) first, then the tools (the panels).
  std::set<int> kept;
  gmsh::vectorpair outside;
  for (std::size_t k = body.size(); k < out_map.size(); ++k)
    for (const auto& piece : out_map[k]) {
      if (piece.first != 2) continue;
      double x, y, z;
      occ::getCenterOfMass(2, piece.second, x, y, z);
      if (cut.frame(Eigen::Vector3d(x, y, z) * to_m).depth > 0.0)
        kept.insert(piece.second);
      else
        outside.push_back(piece);
    }
  if (!outside.empty()) {
    occ::remove(outside, true);
    occ::synchronize();
  }
  if (kept.empty()) throw std::runtime_error("crack embedding: no part of the cut surface lies inside the body");

  CrackEmbedding e;
  e.num_surfaces = static_cast<int>(kept.size());
  e.crack_group = gmsh::model::addPhysicalGroup(2, std::vector<int>(kept.begin(), kept.end()), kCrackGroup);

  // Curves of the cut that lie on the body's outer surface: the cut opens there, so the Crack plugin
  // must split their nodes too. The other boundary curves (the crack front inside the body) stay shared.
  gmsh::vectorpair crack_surfaces;
  for (int s : kept) crack_surfaces.emplace_back(2, s);
  // The outer surface is the combined boundary of all body volumes: faces shared by two pieces (imprinted
  // region interfaces) cancel out, so the cut is not opened where it crosses one of them.
  gmsh::vectorpair volumes;
  gmsh::model::getEntities(volumes, 3);
  std::set<int> outer_faces;
  gmsh::vectorpair outer;
  for (const auto& s : boundary_of(volumes, true))
    if (!kept.count(s.second) && outer_faces.insert(s.second).second) outer.push_back(s);
  std::set<int> outer_curves;
  for (const auto& c : boundary_of(outer, false)) outer_curves.insert(c.second);
  std::vector<int> open;
  for (const auto& c : boundary_of(crack_surfaces, true)) {
    // On the outer surface: a boundary curve of an outer face, or a curve embedded in one (OCC keeps a
    // cut line that ends inside a face as an internal edge of that face, which getBoundary omits).
    std::vector<int> up, down;
    gmsh::model::getAdjacencies(1, c.second, up, down);
    bool on_outer = outer_curves.count(c.second) > 0;
    for (int s : up) on_outer = on_outer || outer_faces.count(s) > 0;
    (on_outer ? open : e.front_curves).push_back(c.second);
  }
  if (!open.empty()) e.open_boundary_group = gmsh::model::addPhysicalGroup(1, open, kOpenBoundaryGroup);
  return e;
}

void split_crack_nodes(const CrackEmbedding& embedding) {
  gmsh::plugin::setNumber("Crack", "Dimension", 2);
  gmsh::plugin::setNumber("Crack", "PhysicalGroup", embedding.crack_group);
  gmsh::plugin::setNumber("Crack", "OpenBoundaryPhysicalGroup", embedding.open_boundary_group);
  gmsh::plugin::run("Crack");
}

int tag_crack_faces(const RuledSurface& cut, TetMesh* mesh) {
  // A face is on the cut when its vertices and centroid lie on the cut surface (OCC puts the nodes on the planar
  // panels to round-off; the extension covers where the surface line bulges above the straight top segments).
  const double tolerance = 1e-6;  // [m]
  int count = 0;
  for (int f = 0; f < mesh->boundary_faces.rows(); ++f) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    bool on_cut = true;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d x = mesh->vertices.row(mesh->boundary_faces(f, k)).transpose();
      centroid += x / 3.0;
      on_cut = on_cut && cut.distance(x) < tolerance;
    }
    if (on_cut && cut.distance(centroid) < tolerance) {
      mesh->face_tags[f] = FaceTag::crack;
      ++count;
    }
  }
  return count;
}

TetMesh mesh_cracked_block(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const RuledSurface& cut,
                           double size, double front_size) {
  constexpr double to_m = 1e-3;  // model in mm, like the built-in lung
  GmshSession session;
  gmsh::model::add("cracked_block");
  const Eigen::Vector3d a = lo / to_m, ext = (hi - lo) / to_m;
  const int box = gmsh::model::occ::addBox(a.x(), a.y(), a.z(), ext.x(), ext.y(), ext.z());
  gmsh::model::occ::synchronize();
  const CrackEmbedding embedding = embed_cut_in_body({box}, cut, to_m);
  const bool graded = front_size > 0.0 && front_size < size && !embedding.front_curves.empty();
  if (graded)
    gmsh::model::mesh::field::setAsBackgroundMesh(add_curve_threshold_field(
        std::vector<double>(embedding.front_curves.begin(), embedding.front_curves.end()), front_size / to_m,
        size / to_m));
  gmsh::option::setNumber("General.NumThreads", 1);
  gmsh::option::setNumber("Mesh.MeshSizeMax", size / to_m);
  gmsh::option::setNumber("Mesh.MeshSizeMin", (graded ? std::min(size / 4, front_size) : size / 4) / to_m);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::model::mesh::generate(3);
  split_crack_nodes(embedding);

  TetMesh mesh = read_gmsh_tets(to_m);  // both lips of the cut are boundary faces now
  tag_crack_faces(cut, &mesh);
  return mesh;
}

}  // namespace core
