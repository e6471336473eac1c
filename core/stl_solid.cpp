#include "core/stl_solid.hpp"

#include <gmsh.h>

#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

namespace core {

int add_stl_solid(const TriangleSurface& surface, double to_m) {
  namespace occ = gmsh::model::occ;
  std::vector<int> points(static_cast<std::size_t>(surface.vertices.rows()));
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i)
    points[static_cast<std::size_t>(i)] =
        occ::addPoint(surface.vertices(i, 0) / to_m, surface.vertices(i, 1) / to_m, surface.vertices(i, 2) / to_m);
  // One OCC line per STL edge, shared by its two triangles (traversed with opposite signs).
  std::map<std::pair<int, int>, int> lines;
  auto oriented_line = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    auto it = lines.find(key);
    if (it == lines.end())
      it = lines.emplace(key, occ::addLine(points[static_cast<std::size_t>(key.first)],
                                           points[static_cast<std::size_t>(key.second)]))
               .first;
    return a == key.first ? it->second : -it->second;
  };
  std::vector<int> faces;
  faces.reserve(static_cast<std::size_t>(surface.triangles.rows()));
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
    const int a = surface.triangles(t, 0), b = surface.triangles(t, 1), c = surface.triangles(t, 2);
    const int loop = occ::addCurveLoop({oriented_line(a, b), oriented_line(b, c), oriented_line(c, a)});
    faces.push_back(occ::addPlaneSurface({loop}));
  }
  const int shell = occ::addSurfaceLoop(faces);
  const int volume = occ::addVolume({shell});
  occ::synchronize();
  double mass = 0.0;
  occ::getMass(3, volume, mass);
  if (!(mass > 0.0)) throw std::runtime_error("STL solid: OpenCASCADE built a volume with no positive mass");
  return volume;
}

}  // namespace core
