// Geometry pipeline: volumes against Gmsh / STL references, tagging invariants, determinism.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <map>

#include "core/case.hpp"
#include "core/geometry.hpp"

namespace {

const std::string kConfigDir = TISSUE_TEST_CONFIG_DIR;

/// Every edge of the boundary is shared by two faces, and the faces point outwards: by the divergence
/// theorem, (1/3) sum over faces of (x . n) dA equals the enclosed volume.
/// Mean length of the tetrahedra's edges (each counted once per tetrahedron using it) for which keep(p, q) holds,
/// and how many there were.
template <class Keep>
std::pair<double, int> mean_edge(const core::TetMesh& m, Keep keep) {
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const Eigen::Vector3d p = m.vertices.row(m.tets(t, a)), q = m.vertices.row(m.tets(t, b));
        if (!keep(p, q)) continue;
        sum += (p - q).norm();
        ++count;
      }
  return {count > 0 ? sum / count : 0.0, count};
}

void expect_closed_outward_boundary(const core::TetMesh& mesh) {
  std::map<std::pair<int, int>, int> edges;
  double flux = 0.0;
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.boundary_faces(f, 2));
    flux += a.dot((b - a).cross(c - a)) / 6.0;
    for (int e = 0; e < 3; ++e) {
      int i = mesh.boundary_faces(f, e), j = mesh.boundary_faces(f, (e + 1) % 3);
      ++edges[{std::min(i, j), std::max(i, j)}];
    }
  }
  for (const auto& [edge, count] : edges) ASSERT_EQ(count, 2) << "boundary edge used " << count << " times";
  EXPECT_NEAR(flux, mesh.volume(), 1e-9 * mesh.volume());
}

TEST(BuiltinLung, TetVolumeMatchesGmshMassWithinHalfPercent) {
  const core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  const core::Geometry g = core::build_geometry(c);
  ASSERT_GT(g.reference_volume, 0.0);
  const double fem_error = std::abs(g.fem_mesh.volume() - g.reference_volume) / g.reference_volume;
  const double cloud_error = std::abs(g.meshless_mesh.volume() - g.reference_volume) / g.reference_volume;
  RecordProperty("fem_volume_relative_error", std::to_string(fem_error));
  RecordProperty("cloud_volume_relative_error", std::to_string(cloud_error));
  std::cout << "built-in lung: Gmsh mass " << g.reference_volume * 1e6 << " cm^3, FEM tets "
            << g.fem_mesh.volume() * 1e6 << " cm^3 (" << fem_error * 100 << " %), cloud cells "
            << g.meshless_mesh.volume() * 1e6 << " cm^3 (" << cloud_error * 100 << " %)\n";
  EXPECT_LT(fem_error, 5e-3);
  EXPECT_LT(cloud_error, 5e-3);
  // About 15 x 17 x 25 cm, the size of a lung lobe.
  const Eigen::Vector3d extent = g.surface.vertices.colwise().maxCoeff() - g.surface.vertices.colwise().minCoeff();
  EXPECT_NEAR(extent.x(), 0.14, 0.015);
  EXPECT_NEAR(extent.y(), 0.17, 0.015);
  EXPECT_NEAR(extent.z(), 0.25, 0.02);
  // The reference surface is closed and encloses the same volume.
  EXPECT_EQ(g.surface.count_non_manifold_edges(), 0);
  EXPECT_NEAR(g.surface.enclosed_volume(), g.reference_volume, 5e-3 * g.reference_volume);
  expect_closed_outward_boundary(g.fem_mesh);
  expect_closed_outward_boundary(g.meshless_mesh);
}

TEST(BuiltinLung, RegionsAreTaggedConsistently) {
  const core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  const core::Geometry g = core::build_geometry(c);
  for (const core::TetMesh* mesh : {&g.fem_mesh, &g.meshless_mesh}) {
    // Fixed faces lie within the selector; the load patch is a disc of radius r around the load centre:
    // its area is close to pi r^2 (a faceted, slightly curved disc with ragged edges).
    for (int f = 0; f < mesh->boundary_faces.rows(); ++f) {
      if (mesh->face_tags[f] != core::FaceTag::fixed) continue;
      for (int k = 0; k < 3; ++k)
        EXPECT_LE((Eigen::Vector3d(mesh->vertices.row(mesh->boundary_faces(f, k))) - c.fixed_region.point).norm(),
                  c.fixed_region.distance + 1e-4);  // imprinted circle: OCC accuracy
    }
    const double area = mesh->tagged_area(core::FaceTag::load);
    const double disc = M_PI * c.load.radius * c.load.radius;
    EXPECT_GT(area, 0.4 * disc);
    EXPECT_LT(area, 1.6 * disc);
    EXPECT_GT(mesh->tagged_area(core::FaceTag::fixed), 0.0);
  }
  // The load centre and every sample lie on the reference surface, within the sampling radius.
  EXPECT_LT(g.surface.closest_point(g.load_centre).distance, 1e-9);
  ASSERT_EQ(g.sample_points.rows(), c.samples.count);
  for (int i = 0; i < g.sample_points.rows(); ++i) {
    const Eigen::Vector3d p = g.sample_points.row(i);
    EXPECT_LT(g.surface.closest_point(p).distance, 1e-9);
    EXPECT_LE((p - g.load_centre).norm(), c.samples.radius * 1.2);
    // Clear of the load-patch edge, where a point-wise comparison is ill-posed (core::kPatchEdgeBandPerLoadRadius).
    EXPECT_GE(std::abs((p - g.load_centre).norm() - c.load.radius), core::kPatchEdgeBandPerLoadRadius * c.load.radius)
        << "sample " << i;
  }
  // Both sides of the band are sampled: under the patch and beyond it.
  const Eigen::VectorXd distance = (g.sample_points.rowwise() - g.load_centre.transpose()).rowwise().norm();
  EXPECT_LT(distance.minCoeff(), c.load.radius);
  EXPECT_GT(distance.maxCoeff(), 2 * c.load.radius);
}

TEST(BuiltinLung, ImprintedRegionsDoNotDependOnTheMeshSize) {
  // The fixed ball and the load ball are imprinted on the body, so every FEM mesh conforms to them: both areas
  // change with the mesh only through the faceting of the curved patch, instead of jumping by whole faces. The
  // faceting is set by the local size under the probe, GeometrySpec::load_patch_size: ungraded (g = 1) 8 and 4.5 mm
  // at h = 16 and 9 mm; with the shipped grading (g = 2, load radius 12 mm) 10.7 and 3.4 mm. Measured: load
  // 423.2 / 443.2 mm^2 ungraded, 405.0 / 446.8 mm^2 graded; fixed 3824 / 3840 mm^2 both ways.
  core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  ASSERT_EQ(c.geometry.load_patch_grading, 2.0) << "the shipped case's grading, which the figures above assume";
  core::GeometryOptions options;
  options.build_node_cloud = false;
  const double disc = M_PI * c.load.radius * c.load.radius;
  for (const double grading : {1.0, 2.0}) {
    c.geometry.load_patch_grading = grading;
    std::vector<double> load_area, fixed_area, patch_size;
    for (double h : {0.016, 0.009}) {
      options.fem_mesh_size = h;
      const core::Geometry g = core::build_geometry(c, options);
      load_area.push_back(g.fem_mesh.tagged_area(core::FaceTag::load));
      fixed_area.push_back(g.fem_mesh.tagged_area(core::FaceTag::fixed));
      patch_size.push_back(c.geometry.load_patch_size(h, c.load.radius));
    }
    std::cout << "grading " << grading << ": load patch " << load_area[0] * 1e6 << " / " << load_area[1] * 1e6
              << " mm^2, fixed " << fixed_area[0] * 1e6 << " / " << fixed_area[1] * 1e6 << " mm^2 at 16 / 9 mm\n";
    SCOPED_TRACE(::testing::Message() << "load_patch_grading " << grading);
    EXPECT_NEAR(fixed_area[0], fixed_area[1], 0.01 * fixed_area[1]);
    // A disc of radius r on a gently curved surface: close to pi r^2 (2.0 % below it at 4.5 mm, 1.2 % at 3.4 mm).
    EXPECT_NEAR(load_area[1], disc, 0.025 * disc);
    // The faceting error falls as the square of the local size (ratios 3.2 ungraded, 9.9 graded, predicted; 3.2
    // and 8.5 measured).
    const double predicted = std::pow(patch_size[0] / patch_size[1], 2);
    const double measured = (disc - load_area[0]) / (disc - load_area[1]);
    EXPECT_GT(measured, 0.75 * predicted) << "the faceting error should fall as the local size squared";
    EXPECT_LT(measured, 1.25 * predicted) << "the faceting error should fall as the local size squared";
  }
}

TEST(BuiltinLung, SamplePointsAndMeshesAreIdenticalAcrossRuns) {
  const core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  core::GeometryOptions options;
  options.build_node_cloud = false;
  const core::Geometry a = core::build_geometry(c, options);
  const core::Geometry b = core::build_geometry(c, options);
  ASSERT_EQ(a.sample_points.rows(), b.sample_points.rows());
  EXPECT_EQ((a.sample_points - b.sample_points).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(a.fem_mesh.num_vertices(), b.fem_mesh.num_vertices());
  EXPECT_EQ((a.fem_mesh.vertices - b.fem_mesh.vertices).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.fem_mesh.tets, b.fem_mesh.tets);
}

TEST(BuiltinLung, CutIsSnappedToTheSurfaceAsARuledSurface) {
  const core::Case c = core::load_case(kConfigDir + "/lung_large.json");
  core::GeometryOptions options;
  options.build_fem_mesh = false;
  options.build_node_cloud = false;
  const core::Geometry g = core::build_geometry(c, options);
  ASSERT_TRUE(g.cut.has_value());
  EXPECT_EQ(g.cut->num_panels(), static_cast<int>(c.cut->polyline.size()) - 1);
  for (const auto& p : g.cut->top()) EXPECT_LT(g.surface.closest_point(p).distance, 1e-9);
  // A ruled surface: each panel's area is |segment x depth direction| * depth.
  double expected = 0.0;
  for (int i = 0; i < g.cut->num_panels(); ++i)
    expected += (g.cut->top()[i + 1] - g.cut->top()[i]).cross(c.cut->direction).norm() * c.cut->depth;
  EXPECT_NEAR(g.cut->area(), expected, 1e-12);
  // Points on either side of a panel have opposite signs of s; the mid-panel point has s = 0.
  const Eigen::Vector3d mid = 0.5 * (g.cut->top()[0] + g.cut->top()[1]) + 0.5 * c.cut->depth * c.cut->direction;
  const core::CutFrame on = g.cut->frame(mid);
  EXPECT_NEAR(on.s, 0.0, 1e-12);
  EXPECT_NEAR(on.depth, 0.5 * c.cut->depth, 1e-12);
  const Eigen::Vector3d n = g.cut->panel_normal(0);
  EXPECT_GT(g.cut->frame(mid + 1e-3 * n).s, 0.0);
  EXPECT_LT(g.cut->frame(mid - 1e-3 * n).s, 0.0);
  EXPECT_NEAR(g.cut->distance(mid + 2e-3 * n), 2e-3, 1e-12);
}

TEST(BuiltinLung, CutBodyIsCrackedAndKeepsItsImprintedRegions) {
  const core::Case c = core::load_case(kConfigDir + "/lung_large.json");
  core::GeometryOptions options;
  options.build_node_cloud = false;
  const core::Geometry g = core::build_geometry(c, options);
  ASSERT_TRUE(g.cut.has_value());
  double crack_area = 0.0, load_area = 0.0;
  for (int f = 0; f < g.fem_mesh.boundary_faces.rows(); ++f) {
    const Eigen::Vector3d a = g.fem_mesh.vertices.row(g.fem_mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = g.fem_mesh.vertices.row(g.fem_mesh.boundary_faces(f, 1));
    const Eigen::Vector3d d = g.fem_mesh.vertices.row(g.fem_mesh.boundary_faces(f, 2));
    const double area = 0.5 * (b - a).cross(d - a).norm();
    if (g.fem_mesh.face_tags[f] == core::FaceTag::crack) crack_area += area;
    if (g.fem_mesh.face_tags[f] == core::FaceTag::load) load_area += area;
  }
  std::cout << "crack faces " << crack_area * 1e6 << " mm^2 (cut " << g.cut->area() * 1e6 << " mm^2), load patch "
            << load_area * 1e6 << " mm^2\n";
  // Both faces of the cut are free boundary: twice the incision area, plus the sliver between the straight
  // top segments and the curved surface line above them (the cut is extended until it pierces the surface).
  EXPECT_NEAR(crack_area, 2.0 * g.cut->area(), 0.05 * 2.0 * g.cut->area());
  // The regions are imprinted on the cut body too, so the load patch is the same disc as without a cut.
  EXPECT_NEAR(load_area, M_PI * c.load.radius * c.load.radius, 0.06 * M_PI * c.load.radius * c.load.radius);
  expect_closed_outward_boundary(g.fem_mesh);
  EXPECT_NEAR(g.fem_mesh.volume(), g.reference_volume, 5e-3 * g.reference_volume);
}

TEST(BuiltinLung, CrackFrontIsGradedOnlyInTheFemMesh) {
  // /geometry/refinement/crack_front f and crack_front_grading g: the edges of the tetrahedra at the crack's front
  // have about f * h * (h / depth)^(g - 1); ungraded (f = g = 1) they have about h. Measured at h = 16 mm, depth 20 mm,
  // f = 0.5, g = 2 (size 6.4 mm): mean edge at the front 7.8 mm graded, 15.6 mm ungraded.
  core::Case c = core::load_case(kConfigDir + "/lung_large.json");
  ASSERT_TRUE(c.cut.has_value());
  core::GeometryOptions options;
  options.build_node_cloud = false;
  options.fem_mesh_size = 0.016;
  auto mean_front_edge = [&](double refinement, double grading, int* cells) {
    c.geometry.crack_front_refinement = refinement;
    c.geometry.crack_front_grading = grading;
    const core::Geometry g = core::build_geometry(c, options);
    *cells = g.fem_mesh.num_tets();
    const auto [mean, count] = mean_edge(g.fem_mesh, [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      return g.cut->front_distance(p) <= 1e-4 || g.cut->front_distance(q) <= 1e-4;  // an edge at the front
    });
    EXPECT_GT(count, 0);
    return mean;
  };
  int ungraded_cells = 0, graded_cells = 0;
  const double ungraded = mean_front_edge(1.0, 1.0, &ungraded_cells);
  const double graded = mean_front_edge(0.5, 2.0, &graded_cells);
  const double expected = c.geometry.crack_front_size(0.016, c.cut->depth);
  std::cout << "mean edge at the crack's front: " << graded * 1e3 << " mm graded (size " << expected * 1e3 << " mm, "
            << graded_cells << " cells), " << ungraded * 1e3 << " mm ungraded (" << ungraded_cells << " cells)\n";
  EXPECT_NEAR(expected, 0.0064, 1e-12);
  EXPECT_NEAR(graded, expected, 0.3 * expected);
  EXPECT_NEAR(ungraded, 0.016, 0.3 * 0.016);
  EXPECT_GT(graded_cells, ungraded_cells);
}

TEST(BuiltinLung, LoadPatchIsRefinedBelowAQuarterOfTheMeshSize) {
  // Gmsh clamps every size field to Mesh.MeshSizeMin, which the mesher sets to h / 4 unless a region asks for less.
  // At h = 16 mm with load_patch_refinement 0.1 and grading 2 the patch asks for 0.1 * 16 * 16 / 12 = 2.13 mm, below
  // h / 4 = 4 mm (the shipped lung studies reach this at h = 5.3 mm: 1.17 mm against 1.33 mm). Measured: the mean
  // edge of the tetrahedra under the probe is 2.60 mm, 1.22 times the size (as elsewhere: 1.16 times at 4 mm); with
  // the floor at h / 4 it was 4.65 mm.
  core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  c.geometry.load_patch_refinement = 0.1;
  c.geometry.load_patch_grading = 2.0;
  core::GeometryOptions options;
  options.build_node_cloud = false;
  options.fem_mesh_size = 0.016;
  const core::Geometry g = core::build_geometry(c, options);
  const auto [mean, count] = mean_edge(g.fem_mesh, [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return (p - g.load_centre).norm() <= c.load.radius && (q - g.load_centre).norm() <= c.load.radius;
  });
  ASSERT_GT(count, 0);
  const double expected = c.geometry.load_patch_size(0.016, c.load.radius);
  std::cout << "mean edge under the probe: " << mean * 1e3 << " mm (size " << expected * 1e3 << " mm, "
            << count << " edge uses)\n";
  EXPECT_NEAR(expected, 0.1 * 0.016 * 0.016 / 0.012, 1e-15);
  EXPECT_GT(mean, 1.1 * expected);
  EXPECT_LT(mean, 1.35 * expected);
}

TEST(BuiltinLung, EdgeZoneGradesOnlyAlongTheLoadPatchsEdge) {
  // /geometry/refinement/load_patch_grading_zone "edge": the graded size only along the patch's edge, the ball keeping
  // load_patch_refinement * h, so a mesh study refines every sample at one rate. At h = 9 mm with g = 2 the edge asks
  // for 0.5 * 9 * 9 / 12 = 3.375 mm and the ball keeps 4.5 mm; "ball" grades the whole ball to 3.375 mm. The edge zone
  // takes the sizes from the size fields alone (Gmsh would otherwise extend the edge's size over the whole patch,
  // which its edge bounds; set_mesh_options), so the rest of the body is coarser too. Measured (mean tetrahedron
  // edge): beside the patch's edge 3.27 mm in both zones; about the load centre 5.07 mm (edge) and 3.96 mm (ball);
  // 25,894 against 71,129 tetrahedra.
  core::Case c = core::load_case(kConfigDir + "/lung_small.json");
  c.geometry.load_patch_grading = 2.0;
  core::GeometryOptions options;
  options.build_node_cloud = false;
  options.fem_mesh_size = 0.009;
  const double graded = c.geometry.load_patch_size(0.009, c.load.radius);
  const double ungraded = c.geometry.load_patch_refinement * 0.009;
  ASSERT_NEAR(graded, 0.003375, 1e-15);
  std::map<std::string, std::pair<double, double>> measured;  // zone -> mean edge beside the patch's edge, at centre
  std::map<std::string, int> tets;
  for (const auto zone : {core::GeometrySpec::LoadPatchGradingZone::edge, core::GeometrySpec::LoadPatchGradingZone::ball}) {
    c.geometry.load_patch_grading_zone = zone;
    const core::Geometry g = core::build_geometry(c, options);
    auto on_surface = [&](const Eigen::Vector3d& p) { return g.surface.closest_point(p).distance < 1e-4; };
    auto beside_edge = [&](const Eigen::Vector3d& p) {
      return std::abs((p - g.load_centre).norm() - c.load.radius) < 0.5 * graded && on_surface(p);
    };
    const auto [edge_mean, edge_count] = mean_edge(g.fem_mesh, [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      return beside_edge(p) && beside_edge(q);
    });
    const auto [centre_mean, centre_count] =
        mean_edge(g.fem_mesh, [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
          return (p - g.load_centre).norm() < 0.5 * c.load.radius && (q - g.load_centre).norm() < 0.5 * c.load.radius;
        });
    ASSERT_GT(edge_count, 0);
    ASSERT_GT(centre_count, 0);
    const std::string name = zone == core::GeometrySpec::LoadPatchGradingZone::edge ? "edge" : "ball";
    std::cout << name << " zone: mean edge beside the patch's edge " << edge_mean * 1e3 << " mm (" << edge_count
              << "), about the load centre " << centre_mean * 1e3 << " mm (" << centre_count << "), "
              << g.fem_mesh.num_tets() << " tets\n";
    measured[name] = {edge_mean, centre_mean};
    tets[name] = g.fem_mesh.num_tets();
  }
  // The band refines less than the whole ball.
  EXPECT_LT(tets["edge"], tets["ball"] / 2);
  // Both zones grade the patch's edge alike; only the ball zone grades the centre (where samples lie).
  EXPECT_NEAR(measured["edge"].first, measured["ball"].first, 0.1 * measured["ball"].first);
  EXPECT_NEAR(measured["ball"].second, 1.2 * graded, 0.15 * graded);
  EXPECT_NEAR(measured["edge"].second, 1.2 * ungraded, 0.15 * ungraded);
}

TEST(RealLobe, TetVolumeEqualsStlEnclosedVolume) {
  const std::string stl = std::string(TISSUE_SHARED_DATA_DIR) + "/lung/lower_lobe_of_left_lung_surface.stl";
  if (!std::filesystem::exists(stl)) GTEST_SKIP() << "real lung STL not found at " << stl << " (../shared absent)";
  const core::Case c = core::load_case(kConfigDir + "/lung_stl.json");
  const core::Geometry g = core::build_geometry(c);
  EXPECT_EQ(g.surface.count_non_manifold_edges(), 0);
  ASSERT_GT(g.reference_volume, 0.0);
  const double error = std::abs(g.fem_mesh.volume() - g.reference_volume) / g.reference_volume;
  std::cout << "real lobe: STL-enclosed " << g.reference_volume * 1e6 << " cm^3, tets " << g.fem_mesh.volume() * 1e6
            << " cm^3 (" << error * 100 << " %), " << g.fem_mesh.num_tets() << " tets\n";
  RecordProperty("stl_volume_relative_error", std::to_string(error));
  // The STL triangles are the solid's faces (core/stl_solid.hpp), so the tets fill exactly the STL volume.
  EXPECT_LT(error, 1e-9);
  expect_closed_outward_boundary(g.fem_mesh);
  // Bounding box from the data README: about 144 x 166 x 263 mm.
  const Eigen::Vector3d extent = g.surface.vertices.colwise().maxCoeff() - g.surface.vertices.colwise().minCoeff();
  EXPECT_NEAR(extent.x(), 0.1436, 0.002);
  EXPECT_NEAR(extent.z(), 0.2632, 0.002);
}

TEST(RealLobe, CutIsCrackedAndRegionsAreImprinted) {
  const std::string stl = std::string(TISSUE_SHARED_DATA_DIR) + "/lung/lower_lobe_of_left_lung_surface.stl";
  if (!std::filesystem::exists(stl)) GTEST_SKIP() << "real lung STL not found at " << stl << " (../shared absent)";
  // lung_stl.json with a 15 mm incision above the probe, cut along the inward direction (0.6, 0, -0.8).
  std::ifstream in(kConfigDir + "/lung_stl.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["geometry"]["stl_file"] = stl;
  j["cut"] = {{"polyline", {{183.9, 158.65, -202.1}, {177.8, 165.6, -200.8}, {171.7, 172.6, -199.4}}},
              {"depth", 15.0},
              {"direction", {0.6, 0.0, -0.8}}};
  const std::filesystem::path config = std::filesystem::temp_directory_path() / "tissue_test_lung_stl_cut.json";
  std::ofstream(config) << j.dump();
  const core::Case c = core::load_case(config.string());
  std::filesystem::remove(config);
  core::GeometryOptions options;
  options.build_node_cloud = false;
  const core::Geometry g = core::build_geometry(c, options);
  ASSERT_TRUE(g.cut.has_value());
  const double crack_area = g.fem_mesh.tagged_area(core::FaceTag::crack);
  const double load_area = g.fem_mesh.tagged_area(core::FaceTag::load);
  std::cout << "real lobe with a cut: crack faces " << crack_area * 1e6 << " mm^2 (cut " << g.cut->area() * 1e6
            << " mm^2), load patch " << load_area * 1e6 << " mm^2\n";
  EXPECT_NEAR(crack_area, 2.0 * g.cut->area(), 0.05 * 2.0 * g.cut->area());  // both lips are free faces
  EXPECT_NEAR(load_area, M_PI * c.load.radius * c.load.radius, 0.06 * M_PI * c.load.radius * c.load.radius);
  expect_closed_outward_boundary(g.fem_mesh);
  EXPECT_NEAR(g.fem_mesh.volume(), g.reference_volume, 1e-9 * g.reference_volume);
}

// The grading shrinks the local size under the probe faster than the mesh size: load_patch_refinement * h *
// (h / r)^(g - 1), r the load radius, so at h = r (the shipped lung cases: 12 mm) nothing changes.
TEST(LoadPatchGrading, RefinesFinerMeshesFasterAndLeavesTheSizeOfTheLoadRadius) {
  core::GeometrySpec g;
  const double r = 0.012;
  EXPECT_DOUBLE_EQ(g.load_patch_size(0.008, r), 0.5 * 0.008);  // g = 1: a fixed fraction, as before
  g.load_patch_grading = 2.0;
  EXPECT_DOUBLE_EQ(g.load_patch_size(0.012, r), 0.5 * 0.012);  // h = r: unchanged
  EXPECT_NEAR(g.load_patch_size(0.008, r), 0.5 * 0.008 * 0.008 / 0.012, 1e-15);
  EXPECT_NEAR(g.load_patch_size(0.018, r), 0.5 * 0.018 * 1.5, 1e-15);
}

}  // namespace
