#include "core/geometry.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <queue>

#include "core/crack_embedding.hpp"
#include "core/gmsh_mesh.hpp"
#include "core/gmsh_session.hpp"
#include "core/gmsh_size_fields.hpp"
#include "core/load_patch_zone.hpp"
#include "core/mesh_ordering.hpp"
#include "core/stl_file.hpp"
#include "core/stl_solid.hpp"

namespace core {
namespace {

constexpr double kSnapTolerance = 0.010;          // points meant to be on the surface: within 10 mm
constexpr double kBuiltinSurfaceSizeMm = 3.0;     // resolution of the built-in lung's reference surface

// ---------------------------------------------------------------------------------------------------
// Gmsh model construction (lengths in the model's own unit: mm for the built-in lung, the STL's unit)

/// A lung-lobe-like solid of about 14 x 17 x 25 cm: an ellipsoid with a flattened medial (mediastinal)
/// face and a concave diaphragmatic base. Returns the OCC volume tag.
int add_builtin_lung() {
  const int body = gmsh::model::occ::addSphere(0, 0, 0, 1);
  gmsh::model::occ::dilate({{3, body}}, 0, 0, 0, 78, 85, 135);
  const int medial = gmsh::model::occ::addBox(62, -300, -300, 300, 600, 600);
  const int diaphragm = gmsh::model::occ::addSphere(0, 0, -135 - 170 + 30, 170);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::cut({{3, body}}, {{3, medial}, {3, diaphragm}}, out, out_map);
  gmsh::model::occ::synchronize();
  if (out.size() != 1 || out[0].first != 3) throw std::runtime_error("built-in lung: boolean cut failed");
  return out[0].second;
}

/// Make the triangle orientation consistent across shared edges, then outward (positive volume).
void orient_outward(TriangleSurface* s) {
  const int n = static_cast<int>(s->triangles.rows());
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (int t = 0; t < n; ++t)
    for (int e = 0; e < 3; ++e) {
      int i = s->triangles(t, e), j = s->triangles(t, (e + 1) % 3);
      edge_faces[{std::min(i, j), std::max(i, j)}].push_back(t);
    }
  auto has_directed_edge = [&](int t, int i, int j) {
    for (int e = 0; e < 3; ++e)
      if (s->triangles(t, e) == i && s->triangles(t, (e + 1) % 3) == j) return true;
    return false;
  };
  std::vector<char> seen(n, 0);
  for (int seed = 0; seed < n; ++seed) {
    if (seen[seed]) continue;
    seen[seed] = 1;
    std::queue<int> q;
    q.push(seed);
    while (!q.empty()) {
      const int t = q.front();
      q.pop();
      for (int e = 0; e < 3; ++e) {
        const int i = s->triangles(t, e), j = s->triangles(t, (e + 1) % 3);
        for (int nb : edge_faces[{std::min(i, j), std::max(i, j)}]) {
          if (nb == t || seen[nb]) continue;
          // consistent neighbours traverse the shared edge in opposite directions
          if (has_directed_edge(nb, i, j)) std::swap(s->triangles(nb, 1), s->triangles(nb, 2));
          seen[nb] = 1;
          q.push(nb);
        }
      }
    }
  }
  if (s->enclosed_volume() < 0)
    for (int t = 0; t < n; ++t) std::swap(s->triangles(t, 1), s->triangles(t, 2));
}

/// `finest`: the smallest local size a size field asks for. Gmsh clamps every field to [MeshSizeMin, MeshSizeMax], so
/// the floor must not cut off a graded region (at h = 5.3 mm the load patch's 1.17 mm would become 1.33 mm).
/// `sizes_from_fields_only`: Gmsh's default extends the sizes of a face's boundary curves into its interior, so a face
/// bounded by a finely graded curve (the load patch, inside its edge band) is meshed at that size throughout. The load
/// patch's edge zone (GeometrySpec::LoadPatchGradingZone::edge) wants the band alone, so it turns that off; every
/// other mesh keeps the default, so that the shipped meshes do not change.
void set_mesh_options(double size, double finest = std::numeric_limits<double>::infinity(),
                      bool sizes_from_fields_only = false) {
  gmsh::option::setNumber("General.NumThreads", 1);  // deterministic meshes
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", sizes_from_fields_only ? 0 : 1);
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  gmsh::option::setNumber("Mesh.MeshSizeMin", std::min(size / 4, finest));
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  gmsh::option::setNumber("Mesh.Algorithm", 6);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
}

/// Mesh the current model's volume at `size` (model units), its size fields allowed down to `finest` (refine_regions),
/// and return linear tets in metres.
/// `after_generate` may edit the mesh before it is read (the FEM crack splits its nodes there).
TetMesh mesh_volume(double size, double finest, bool sizes_from_fields_only, double to_m,
                    const std::function<void()>& after_generate = {}) {
  set_mesh_options(size, finest, sizes_from_fields_only);
  gmsh::model::mesh::generate(3);
  if (after_generate) after_generate();
  return read_gmsh_tets(to_m);
}

// Vertices that Gmsh placed on an imprinted region boundary lie on it only up to round-off.
constexpr double kRegionTolerance = 5e-5;  // [m]; OCC intersection curves are accurate to ~1e-3 mm

bool in_fixed_region(const FixedRegionSpec& r, const Eigen::Vector3d& x) {
  return r.depth_inside(x) >= -kRegionTolerance;
}

/// Tag fixed and load faces; errors name the case file and the JSON path of the selector. The mesh conforms to
/// the imprinted load circle (and fixed ball), so a face is in a region exactly when its three vertices are.
void tag_regions(const Case& c, const Eigen::Vector3d& load_centre, const Eigen::Vector3d& load_normal,
                 const char* which, TetMesh* mesh) {
  int n_fixed = 0, n_load = 0, n_overlap = 0;
  for (int f = 0; f < mesh->boundary_faces.rows(); ++f) {
    bool all_fixed = true, all_loaded = true;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d x = mesh->vertices.row(mesh->boundary_faces(f, k));
      all_fixed = all_fixed && in_fixed_region(c.fixed_region, x);
      all_loaded = all_loaded && (x - load_centre).norm() <= c.load.radius + kRegionTolerance;
    }
    const Eigen::Vector3d a = mesh->vertices.row(mesh->boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh->vertices.row(mesh->boundary_faces(f, 1));
    const Eigen::Vector3d cc = mesh->vertices.row(mesh->boundary_faces(f, 2));
    const Eigen::Vector3d normal = (b - a).cross(cc - a).normalized();
    const bool in_load = all_loaded && normal.dot(load_normal) > 0.0;
    if (all_fixed) {
      mesh->face_tags[f] = FaceTag::fixed;
      for (int k = 0; k < 3; ++k) mesh->vertex_fixed[mesh->boundary_faces(f, k)] = 1;
      ++n_fixed;
      if (in_load) ++n_overlap;
    } else if (in_load) {
      mesh->face_tags[f] = FaceTag::load;
      ++n_load;
    }
  }
  if (n_fixed == 0)
    throw CaseError(c.source_file, "/fixed_region",
                    fmt::format("selects no boundary face of the {} (every face needs its three vertices "
                                "inside the region); expected a larger distance or a point on the surface",
                                which));
  if (n_load == 0)
    throw CaseError(c.source_file, "/load/radius",
                    fmt::format("the load patch holds no boundary face of the {}; expected a radius larger "
                                "than the mesh size ({:.3g} mm)",
                                which, c.load.radius * 1e3));
  if (n_overlap > 0)
    throw CaseError(c.source_file, "/load",
                    "the load patch overlaps the fixed region; expected them to be disjoint");
}

/// Deterministic sample points (paper §5.4): `spec.count` surface points spread evenly over the disc of radius
/// `spec.radius` around the load centre, in its tangent plane (a sunflower spiral: equal area per point), then
/// snapped to the surface. The annulus within `band` of the load-patch circle (radius `load_radius`) is left out
/// of the disc, and a point that lands in the band after snapping (the surface curves) is moved radially until it
/// leaves it.
PointMatrix choose_samples(const TriangleSurface& surface, const SampleSpec& spec, const Eigen::Vector3d& centre,
                           const Eigen::Vector3d& normal, double load_radius, double band) {
  Eigen::Vector3d helper = Eigen::Vector3d::UnitX();
  if (std::abs(normal.x()) > 0.9) helper = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d t1 = normal.cross(helper).normalized();
  const Eigen::Vector3d t2 = normal.cross(t1);
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  // The disc without the annulus [inner, outer]: equal area per point over [0, inner] and [outer, R].
  const double R = spec.radius;
  const double inner = std::clamp(load_radius - band, 0.0, R), outer = std::clamp(load_radius + band, inner, R);
  const double inner_area = inner * inner, area = inner_area + R * R - outer * outer;  // over pi
  auto radius_at = [&](double fraction) {                                             // fraction of the area
    const double a = fraction * area;
    return a <= inner_area ? std::sqrt(a) : std::sqrt(a - inner_area + outer * outer);
  };
  auto snap = [&](double r, double theta) -> Eigen::Vector3d {
    return surface.closest_point(centre + r * (std::cos(theta) * t1 + std::sin(theta) * t2)).point;
  };
  PointMatrix samples(spec.count, 3);
  for (int i = 0; i < spec.count; ++i) {
    const double theta = i * golden_angle;
    double r = area > 0.0 ? radius_at((i + 0.5) / spec.count) : R * std::sqrt((i + 0.5) / spec.count);
    Eigen::Vector3d x = snap(r, theta);
    // The band is measured as compare measures it: | |x - centre| - load_radius | in 3-D.
    for (int attempt = 0; attempt < 8; ++attempt) {
      const double d = (x - centre).norm();
      if (std::abs(d - load_radius) >= band) break;
      const double target = r < load_radius ? load_radius - 1.05 * band : load_radius + 1.05 * band;
      r = std::max(0.0, r + (target - d));
      x = snap(r, theta);
    }
    samples.row(i) = x.transpose();
  }
  return samples;
}

/// Read, check and orient the STL surface (metres). Errors point at /geometry/stl_file.
TriangleSurface load_stl_surface(const Case& c) {
  const std::string& file = c.geometry.stl_file;
  if (const std::string problem = check_stl_layout(file); !problem.empty())
    throw CaseError(c.source_file, "/geometry/stl_file", problem);
  try {
    gmsh::merge(file);
  } catch (...) {
    throw CaseError(c.source_file, "/geometry/stl_file",
                    fmt::format("expected a readable STL surface, but Gmsh could not read \"{}\"", file));
  }
  TriangleSurface surface = read_gmsh_triangles(c.geometry.stl_unit_to_m);
  gmsh::clear();
  if (surface.triangles.rows() < 4)
    throw CaseError(c.source_file, "/geometry/stl_file",
                    fmt::format("expected a closed triangulated surface, but \"{}\" holds {} triangles", file,
                                surface.triangles.rows()));
  const int open_edges = surface.count_non_manifold_edges();
  if (open_edges > 0)
    throw CaseError(c.source_file, "/geometry/stl_file",
                    fmt::format("expected a closed surface (every edge shared by exactly two triangles), but "
                                "\"{}\" has {} open or non-manifold edges",
                                file, open_edges));
  orient_outward(&surface);
  return surface;
}

/// Reference surface and volume for the case (the Gmsh model is left empty for STL input).
TriangleSurface reference_surface(const Case& c, double* reference_volume) {
  if (c.geometry.source == GeometrySpec::Source::builtin_lung) {
    gmsh::clear();
    const int volume = add_builtin_lung();
    double mass = 0.0;
    gmsh::model::occ::getMass(3, volume, mass);
    if (reference_volume) *reference_volume = mass * 1e-9;
    set_mesh_options(kBuiltinSurfaceSizeMm);
    gmsh::model::mesh::generate(2);
    TriangleSurface surface = read_gmsh_triangles(1e-3);
    orient_outward(&surface);
    gmsh::model::mesh::clear();
    return surface;
  }
  TriangleSurface surface = load_stl_surface(c);
  if (reference_volume) *reference_volume = surface.enclosed_volume();
  return surface;
}

/// Imprint the fixed region (near_point) and the load patch on the built-in lung by fragmenting the body
/// with the selector balls, so every mesh conforms to the region boundaries. The tagged fixed and loaded
/// areas then do not change with the mesh size, which the FEM mesh-convergence study needs. The pieces of
/// the balls outside the body are removed. Returns the OCC volumes that now make up the body.
std::vector<int> imprint_regions(const Case& c, int volume, const Eigen::Vector3d& load_centre) {
  gmsh::vectorpair tools;
  if (c.fixed_region.kind == FixedRegionSpec::Kind::near_point) {
    const Eigen::Vector3d p = c.fixed_region.point / 1e-3;
    tools.push_back({3, gmsh::model::occ::addSphere(p.x(), p.y(), p.z(), c.fixed_region.distance / 1e-3)});
  }
  const Eigen::Vector3d q = load_centre / 1e-3;
  tools.push_back({3, gmsh::model::occ::addSphere(q.x(), q.y(), q.z(), c.load.radius / 1e-3)});
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::fragment({{3, volume}}, tools, out, out_map);
  std::vector<int> body;
  for (const auto& piece : out_map.at(0)) body.push_back(piece.second);
  gmsh::vectorpair outside;
  for (const auto& piece : out)
    if (piece.first == 3 && std::find(body.begin(), body.end(), piece.second) == body.end())
      outside.push_back(piece);
  gmsh::model::occ::remove(outside, /*recursive=*/true);
  gmsh::model::occ::synchronize();
  return body;
}

/// A Gmsh Ball size field: `inside` within `radius` of `centre`, growing to `outside` over `thickness`.
int add_ball_field(const Eigen::Vector3d& centre, double radius, double thickness, double inside, double outside) {
  const int ball = gmsh::model::mesh::field::add("Ball");
  gmsh::model::mesh::field::setNumber(ball, "XCenter", centre.x());
  gmsh::model::mesh::field::setNumber(ball, "YCenter", centre.y());
  gmsh::model::mesh::field::setNumber(ball, "ZCenter", centre.z());
  gmsh::model::mesh::field::setNumber(ball, "Radius", radius);
  gmsh::model::mesh::field::setNumber(ball, "Thickness", thickness);
  gmsh::model::mesh::field::setNumber(ball, "VIn", inside);
  gmsh::model::mesh::field::setNumber(ball, "VOut", outside);
  return ball;
}

/// True when every boundary curve of model face `face` lies within `radius` of `centre` (model units): the face is a
/// piece of the surface inside the ball. (A face's centre of mass would not do: a large face with the imprinted patch
/// as a hole has its centre inside the ball too.) The imprint's curves are exact circles on a plane (the built-in
/// lung's medial face) but OpenCASCADE's approximations of the sphere's intersection on a curved surface (its lateral
/// face, under the probe), hence the relative tolerance kOnBallTolerance.
constexpr double kOnBallTolerance = 1e-3;
bool face_inside_ball(int face, const Eigen::Vector3d& centre, double radius) {
  constexpr int kSamplesPerCurve = 8;
  gmsh::vectorpair curves;
  gmsh::model::getBoundary({{2, face}}, curves, /*combined=*/false, /*oriented=*/false);
  for (const auto& curve : curves) {
    std::vector<double> lo, hi, xyz;
    gmsh::model::getParametrizationBounds(1, std::abs(curve.second), lo, hi);
    std::vector<double> params;
    for (int k = 0; k <= kSamplesPerCurve; ++k) params.push_back(lo[0] + (hi[0] - lo[0]) * k / kSamplesPerCurve);
    gmsh::model::getValue(1, std::abs(curve.second), params, xyz);
    for (std::size_t k = 0; k + 2 < xyz.size(); k += 3)
      if ((Eigen::Vector3d(xyz[k], xyz[k + 1], xyz[k + 2]) - centre).norm() > radius * (1.0 + kOnBallTolerance))
        return false;
  }
  return true;
}

/// The curves where the part of the body's outer surface inside a ball (an imprinted region: the fixed region or the
/// load patch) meets the rest of the surface, from the current model (after every fragment: the region imprints and
/// a crack). Model units. The region is the outer faces inside the ball; its combined boundary is the edge.
std::vector<double> imprinted_patch_edge_curves(const Eigen::Vector3d& centre, double radius) {
  gmsh::vectorpair volumes, outer, patch, edge;
  gmsh::model::getEntities(volumes, 3);
  gmsh::model::getBoundary(volumes, outer, /*combined=*/true, /*oriented=*/false);
  for (const auto& face : outer)
    if (face_inside_ball(std::abs(face.second), centre, radius)) patch.emplace_back(2, std::abs(face.second));
  std::vector<double> curves;
  if (patch.empty()) return curves;
  gmsh::model::getBoundary(patch, edge, /*combined=*/true, /*oriented=*/false);
  for (const auto& curve : edge) curves.push_back(std::abs(curve.second));
  return curves;
}

/// The clamp's edge: where the imprinted near_point fixed region meets the rest of the body's surface.
std::vector<double> clamp_edge_curves(const Case& c) {
  return imprinted_patch_edge_curves(c.fixed_region.point / 1e-3, c.fixed_region.distance / 1e-3);
}

/// True when the FEM mesh grades the load patch only along its edge (the node cloud is never graded).
bool grades_only_the_patch_edge(const Case& c, bool fem_mesh) {
  return fem_mesh && c.geometry.load_patch_grading_zone == GeometrySpec::LoadPatchGradingZone::edge;
}

/// The fields that refine under the probe (core/load_patch_zone.hpp). Returns their tags and the finest size.
///  * the ball of kLoadPatchBallRadii * r: load_patch_refinement * size, growing to size over one load radius; on the
///    FEM mesh with the grading zone `ball`, GeometrySpec::load_patch_size instead (graded like h^g);
///  * on the FEM mesh with the grading zone `edge`, where the graded size is below the ball's: that size along the
///    patch's edge (the traction jump), growing to the mesh size over one mesh size (so to the ball's size within
///    about half of that).
std::pair<std::vector<double>, double> load_patch_fields(const Case& c, const Eigen::Vector3d& load_centre,
                                                         double size, bool fem_mesh) {
  const double r = c.load.radius / 1e-3;
  const double ungraded = c.geometry.load_patch_refinement * size;
  const double graded = fem_mesh ? c.geometry.load_patch_size(size, r) : ungraded;
  const bool edge_band = grades_only_the_patch_edge(c, fem_mesh);
  const double ball_size = edge_band ? ungraded : graded;
  std::vector<double> fields{
      static_cast<double>(add_ball_field(load_centre / 1e-3, kLoadPatchBallRadii * r, r, ball_size, size))};
  double finest = ball_size;
  if (edge_band && graded < ungraded) {
    const std::vector<double> edge = imprinted_patch_edge_curves(load_centre / 1e-3, r);
    if (edge.empty())
      throw CaseError(c.source_file, "/geometry/refinement/load_patch_grading_zone",
                      "the load patch's imprint on the surface has no edge curve to grade the mesh along; expected "
                      "\"ball\" for this body (or a load point whose patch lies on the surface)");
    fields.push_back(add_curve_threshold_field(edge, graded, size));  // the ball's field keeps `ungraded` within it
    finest = graded;
  }
  return {fields, finest};
}

/// Refine where the solution is sensitive to the region boundaries, in proportion to the mesh size so that every level
/// of a mesh study refines there too (model units, mm):
///  * elements of load_patch_refinement * size within kLoadPatchBallRadii * r of the load centre: the patch, its
///    edge (where the traction jumps) and the samples; on the FEM mesh graded by load_patch_grading over the ball or
///    along the patch's edge (load_patch_fields);
///  * elements of fixed_region_refinement * size along the edge of a near_point fixed region (the clamp's edge,
///    where most of the lung's error lives), growing to the mesh size over one mesh size (`tissue case check` prints the node
///    counts this costs);
///  * on a cracked FEM mesh, elements of GeometrySpec::crack_front_size along the crack's front, growing to the mesh
///    size over one mesh size (when that size is below the mesh size).
/// Returns the smallest of these sizes (model units), for the mesher's size floor (set_mesh_options).
double refine_regions(const Case& c, const Eigen::Vector3d& load_centre, double size, bool fem_mesh,
                      const CrackEmbedding* crack) {
  auto [fields, finest] = load_patch_fields(c, load_centre, size, fem_mesh);
  if (c.fixed_region.kind == FixedRegionSpec::Kind::near_point) {
    const std::vector<double> edge = clamp_edge_curves(c);
    if (!edge.empty()) {
      fields.push_back(add_curve_threshold_field(edge, c.geometry.fixed_region_refinement * size, size));
      finest = std::min(finest, c.geometry.fixed_region_refinement * size);
    }
  }
  if (fem_mesh && crack && c.cut && !crack->front_curves.empty()) {
    const double front_size = c.geometry.crack_front_size(size, c.cut->depth / 1e-3);
    if (front_size < size) {
      fields.push_back(add_curve_threshold_field(
          std::vector<double>(crack->front_curves.begin(), crack->front_curves.end()), front_size, size));
      finest = std::min(finest, front_size);
    }
  }
  const int min_field = gmsh::model::mesh::field::add("Min");
  gmsh::model::mesh::field::setNumbers(min_field, "FieldsList", fields);
  gmsh::model::mesh::field::setAsBackgroundMesh(min_field);
  return finest;
}

/// Tetrahedra of the case's body at `size` [m]. Both geometry sources become OpenCASCADE solids in mm
/// (the built-in lung, or the STL's triangles as planar faces), so both get the same treatment: the regions
/// are imprinted, the mesh is refined around them, and a cut is embedded and cracked (FEM mesh only).
TetMesh mesh_body(const Case& c, const TriangleSurface& surface, double size, const Eigen::Vector3d& load_centre,
                  bool fem_mesh, const RuledSurface* cut = nullptr) {
  constexpr double to_m = 1e-3;  // model units: mm
  gmsh::clear();
  const int solid = c.geometry.source == GeometrySpec::Source::builtin_lung ? add_builtin_lung()
                                                                             : add_stl_solid(surface, to_m);
  const std::vector<int> body = imprint_regions(c, solid, load_centre);
  // The FEM crack (core/crack_embedding.hpp): embed the cut in the imprinted body, mesh, then duplicate
  // its nodes.
  const std::optional<CrackEmbedding> crack =
      cut ? std::optional(embed_cut_in_body(body, *cut, to_m)) : std::nullopt;
  // After the last fragment, so that the clamp's edge curves are the ones that get meshed.
  const double finest = refine_regions(c, load_centre, size / to_m, fem_mesh, crack ? &*crack : nullptr);
  TetMesh mesh;
  try {
    mesh = mesh_volume(size / to_m, finest, grades_only_the_patch_edge(c, fem_mesh), to_m, [&] {
      if (crack) split_crack_nodes(*crack);
    });
  } catch (const std::string& gmsh_error) {  // the Gmsh SDK throws its last error as a string
    const std::string what = fmt::format("Gmsh could not mesh the body at {:.3g} mm: {}", size * 1e3, gmsh_error);
    if (cut)
      throw CaseError(c.source_file, "/cut",
                      what + "; expected an incision that crosses the surface at a clear angle (try another direction "
                             "or depth)");
    throw std::runtime_error(what);
  }
  return mesh;
}

SurfacePoint snap(const Case& c, const TriangleSurface& s, const Eigen::Vector3d& x, double tolerance,
                  const std::string& json_path, const char* what) {
  const SurfacePoint p = s.closest_point(x);
  if (p.distance > tolerance)
    throw CaseError(c.source_file, json_path,
                    fmt::format("{} is {:.1f} mm from the body surface; expected a point on the surface "
                                "(within {:.1f} mm)",
                                what, p.distance * 1e3, tolerance * 1e3));
  return p;
}

/// The incision must end inside the tissue: below every point of its top line, the body must be thicker than the
/// depth along the cut direction (a cut through the whole body would split it in two, which neither model treats).
void check_cut_depth(const Case& c, const TriangleSurface& surface, const RuledSurface& cut) {
  constexpr int kSamplesPerSegment = 4;
  constexpr double kInset = 1e-4;  // [m] start the ray just inside the surface
  double thinnest = std::numeric_limits<double>::infinity();
  Eigen::Vector3d where = cut.top().front();
  for (int j = 0; j < cut.num_panels(); ++j)
    for (int k = 0; k <= kSamplesPerSegment; ++k) {
      const Eigen::Vector3d p =
          cut.top()[j] + (static_cast<double>(k) / kSamplesPerSegment) * (cut.top()[j + 1] - cut.top()[j]);
      const double thickness = kInset + surface.ray_hit(p + kInset * cut.direction(), cut.direction());
      if (thickness < thinnest) {
        thinnest = thickness;
        where = p;
      }
    }
  if (cut.depth() >= thinnest)
    throw CaseError(c.source_file, "/cut/depth",
                    fmt::format("an incision {:.1f} mm deep leaves the body: below ({:.1f}, {:.1f}, {:.1f}) mm the "
                                "tissue is only {:.1f} mm thick along the cut direction; expected a depth below that",
                                cut.depth() * 1e3, where.x() * 1e3, where.y() * 1e3, where.z() * 1e3, thinnest * 1e3));
}

}  // namespace

TriangleSurface build_reference_surface(const Case& c, double* reference_volume) {
  GmshSession session;
  return reference_surface(c, reference_volume);
}

Geometry build_geometry(const Case& c, const GeometryOptions& options) {
  GmshSession session;
  Geometry g;
  g.surface = reference_surface(c, &g.reference_volume);

  // Cheap checks on the exact surface first, so a bad case fails before any volume meshing.
  const double load_tolerance = std::max(c.load.radius, kSnapTolerance);
  const SurfacePoint load = snap(c, g.surface, c.load.point, load_tolerance, "/load/point", "the load point");
  g.load_centre = load.point;
  g.load_normal = load.normal;
  if (c.fixed_region.kind == FixedRegionSpec::Kind::near_plane) {
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < g.surface.vertices.rows(); ++i)
      nearest = std::min(nearest, std::abs((Eigen::Vector3d(g.surface.vertices.row(i)) - c.fixed_region.point)
                                               .dot(c.fixed_region.normal)));
    if (nearest > c.fixed_region.distance)
      throw CaseError(c.source_file, "/fixed_region",
                      fmt::format("selects no part of the surface: the body is {:.1f} mm from the plane but the "
                                  "distance is {:.1f} mm; expected a distance larger than that",
                                  nearest * 1e3, c.fixed_region.distance * 1e3));
  } else {
    const SurfacePoint p = g.surface.closest_point(c.fixed_region.point);
    if (p.distance > c.fixed_region.distance)
      throw CaseError(c.source_file, "/fixed_region",
                      fmt::format("selects no part of the surface: the point is {:.1f} mm from the surface but "
                                  "the distance is {:.1f} mm; expected a distance larger than that",
                                  p.distance * 1e3, c.fixed_region.distance * 1e3));
  }
  if (c.cut) {
    std::vector<Eigen::Vector3d> top;
    for (std::size_t i = 0; i < c.cut->polyline.size(); ++i)
      top.push_back(snap(c, g.surface, c.cut->polyline[i], kSnapTolerance,
                         "/cut/polyline/" + std::to_string(i), "the cut point")
                        .point);
    for (std::size_t i = 0; i < top.size(); ++i)
      if (g.surface.closest_point(top[i]).normal.dot(c.cut->direction) > 0.0)
        throw CaseError(c.source_file, "/cut/direction",
                        fmt::format("points out of the body at cut point {} (/cut/polyline/{}); expected a direction "
                                    "into the tissue at every point of the incision",
                                    i, i));
    try {
      g.cut.emplace(top, c.cut->direction, c.cut->depth);
    } catch (const std::invalid_argument& e) {
      throw CaseError(c.source_file, "/cut/polyline", std::string("expected a simple incision: ") + e.what());
    }
    check_cut_depth(c, g.surface, *g.cut);
  }
  g.sample_points = choose_samples(g.surface, c.samples, g.load_centre, g.load_normal, c.load.radius,
                                   kPatchEdgeBandPerLoadRadius * c.load.radius);

  if (options.build_fem_mesh) {
    const double h = options.fem_mesh_size.value_or(c.geometry.mesh_size);
    g.fem_mesh = mesh_body(c, g.surface, h, g.load_centre, /*fem_mesh=*/true, g.cut ? &*g.cut : nullptr);  // only the FEM mesh is cracked
    tag_regions(c, g.load_centre, g.load_normal, "FEM mesh", &g.fem_mesh);
    if (g.cut) tag_crack_faces(*g.cut, &g.fem_mesh);
    order_for_locality(&g.fem_mesh);  // cells, hence the FEM's DoFs, numbered for cache use (core/mesh_ordering.hpp)
  }
  if (options.build_node_cloud) {
    g.meshless_mesh = mesh_body(c, g.surface, c.meshless.node_spacing, g.load_centre, /*fem_mesh=*/false);
    tag_regions(c, g.load_centre, g.load_normal, "meshless node cloud", &g.meshless_mesh);
    order_for_locality(&g.meshless_mesh);  // the EFG assembly's cache use (core/mesh_ordering.hpp)
  }
  return g;
}

}  // namespace core
