#include "meshless/lrpim/surface_body.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/surface_query.hpp"
#include "meshless/mls/node_search.hpp"

namespace meshless::lrpim {

// The triangles' centroids in a KD-tree: a triangle is within r of x only if its centroid is within
// r + (its largest centroid-to-corner distance), so one radius query with the largest such distance finds
// every candidate. The centroid matrix sits in the same heap object as the tree that references it.
struct SurfaceBody::Index {
  core::PointMatrix centroids;
  double max_reach = 0.0;
  std::unique_ptr<NodeSearch> search;
};

SurfaceBody::SurfaceBody(core::PointMatrix vertices, core::TriMatrix triangles, std::vector<int> labels)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)), labels_(std::move(labels)) {
  const int nt = num_triangles();
  if (static_cast<int>(labels_.size()) != nt)
    throw std::invalid_argument("SurfaceBody: one label per triangle expected");
  if (nt < 4) throw std::invalid_argument("SurfaceBody: a closed surface needs at least 4 triangles");
  auto index = std::make_shared<Index>();
  index->centroids.resize(nt, 3);
  normals_.resize(nt);
  areas_.resize(nt);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k)
      if (triangles_(t, k) < 0 || triangles_(t, k) >= vertices_.rows()) {
        std::ostringstream s;
        s << "SurfaceBody: triangle " << t << " names vertex " << triangles_(t, k) << " of " << vertices_.rows();
        throw std::invalid_argument(s.str());
      }
    if (labels_[t] < 0) throw std::invalid_argument("SurfaceBody: labels must be >= 0");
    const Eigen::Vector3d a = corner(t, 0), b = corner(t, 1), c = corner(t, 2);
    const Eigen::Vector3d n = (b - a).cross(c - a);
    areas_[t] = 0.5 * n.norm();
    if (!(areas_[t] > 0.0)) {
      std::ostringstream s;
      s << "SurfaceBody: triangle " << t << " has zero area (a degenerate boundary face)";
      throw std::invalid_argument(s.str());
    }
    normals_[t] = n.normalized();
    const Eigen::Vector3d g = (a + b + c) / 3.0;
    index->centroids.row(t) = g.transpose();
    index->max_reach = std::max({index->max_reach, (a - g).norm(), (b - g).norm(), (c - g).norm()});
  }
  index->search = std::make_unique<NodeSearch>(index->centroids);
  index_ = std::move(index);
}

SurfaceBody SurfaceBody::from_box(const BoxBody& box) {
  core::PointMatrix v(8, 3);
  for (int i = 0; i < 8; ++i)
    v.row(i) << (i & 1 ? box.hi.x() : box.lo.x()), (i & 2 ? box.hi.y() : box.lo.y()), (i & 4 ? box.hi.z() : box.lo.z());
  // Each face as the quad (p0 p1 p2 p3) counter-clockwise seen from outside, split along p0-p2.
  const int quads[kBoxFaces][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  core::TriMatrix t(12, 3);
  std::vector<int> labels(12);
  for (int f = 0; f < kBoxFaces; ++f) {
    t.row(2 * f) << quads[f][0], quads[f][1], quads[f][2];
    t.row(2 * f + 1) << quads[f][0], quads[f][2], quads[f][3];
    labels[2 * f] = labels[2 * f + 1] = f;
  }
  return SurfaceBody(std::move(v), std::move(t), std::move(labels));
}

SurfaceBody SurfaceBody::from_mesh_boundary(const core::TetMesh& mesh) {
  std::vector<int> new_id(mesh.num_vertices(), -1);
  int nv = 0;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (new_id[mesh.boundary_faces(f, k)] < 0) new_id[mesh.boundary_faces(f, k)] = nv++;
  core::PointMatrix v(nv, 3);
  for (int i = 0; i < mesh.num_vertices(); ++i)
    if (new_id[i] >= 0) v.row(new_id[i]) = mesh.vertices.row(i);
  core::TriMatrix t(mesh.boundary_faces.rows(), 3);
  std::vector<int> labels(t.rows());
  for (Eigen::Index f = 0; f < t.rows(); ++f) {
    for (int k = 0; k < 3; ++k) t(f, k) = new_id[mesh.boundary_faces(f, k)];
    labels[f] = static_cast<int>(mesh.face_tags[f]);
  }
  return SurfaceBody(std::move(v), std::move(t), std::move(labels));
}

double SurfaceBody::labelled_area(int label) const {
  double a = 0.0;
  for (int t = 0; t < num_triangles(); ++t)
    if (labels_[t] == label) a += areas_[t];
  return a;
}

void SurfaceBody::triangles_near(const Eigen::Vector3d& x, double radius, std::vector<int>* out) const {
  out->clear();
  thread_local std::vector<NodeHit> hits;
  index_->search->within_radius(x, radius + index_->max_reach, &hits);
  for (const NodeHit& h : hits) {
    const int t = h.node;
    if ((core::closest_point_on_triangle(x, corner(t, 0), corner(t, 1), corner(t, 2)) - x).norm() < radius)
      out->push_back(t);
  }
}

double SurfaceBody::distance_to_surface(const Eigen::Vector3d& x, double search_radius) const {
  double best = std::numeric_limits<double>::infinity();
  thread_local std::vector<NodeHit> hits;
  index_->search->within_radius(x, search_radius + index_->max_reach, &hits);
  for (const NodeHit& h : hits)
    best = std::min(best, (core::closest_point_on_triangle(x, corner(h.node, 0), corner(h.node, 1), corner(h.node, 2)) - x).norm());
  return best <= search_radius ? best : std::numeric_limits<double>::infinity();
}

double triangle_solid_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  const Eigen::Vector3d x = a - p, y = b - p, z = c - p;
  const double lx = x.norm(), ly = y.norm(), lz = z.norm();
  const double numerator = x.dot(y.cross(z));
  const double denominator = lx * ly * lz + x.dot(y) * lz + x.dot(z) * ly + y.dot(z) * lx;
  return 2.0 * std::atan2(numerator, denominator);
}

LocalSurface::LocalSurface(const SurfaceBody& body, const Eigen::Vector3d& x, double radius, double tolerance)
    : body_(&body), x_(x), radius_(radius) {
  body.triangles_near(x, radius, &near_);
  std::sort(near_.begin(), near_.end());  // a deterministic order, whatever the tree returned
  for (int t : near_) {
    const double d = (core::closest_point_on_triangle(x, body.corner(t, 0), body.corner(t, 1), body.corner(t, 2)) - x).norm();
    (d < tolerance ? touching_ : crossing_).push_back(t);
  }
}

void LocalSurface::ray_segments(const Eigen::Vector3d& d, double r_max, std::vector<RaySegment>* out) const {
  out->clear();
  bool inside = true;
  if (!touching_.empty()) {
    // Seen from a point just along d, the touching triangles form the body's local cone at x (they are the
    // whole neighbourhood of x on the surface); 1e-7 r is far below their size and far above round-off.
    const Eigen::Vector3d p = x_ + 1e-7 * radius_ * d;
    double omega = 0.0;
    for (int t : touching_) omega += triangle_solid_angle(p, body_->corner(t, 0), body_->corner(t, 1), body_->corner(t, 2));
    inside = omega > 0.0;
  }
  // Crossings (distance, +1 leaving / -1 entering) within (0, r_max].
  thread_local std::vector<std::pair<double, int>> crossings;
  crossings.clear();
  constexpr double kBarycentricSlack = 1e-12;  // an edge or vertex hit counts on every triangle sharing it
  for (int t : crossing_) {
    const Eigen::Vector3d a = body_->corner(t, 0), e1 = body_->corner(t, 1) - a, e2 = body_->corner(t, 2) - a;
    const Eigen::Vector3d pvec = d.cross(e2);
    const double det = e1.dot(pvec);
    if (std::abs(det) <= 1e-14 * e1.norm() * e2.norm()) continue;  // the ray runs in the triangle's plane
    const double inv = 1.0 / det;
    const Eigen::Vector3d tvec = x_ - a;
    const double u = tvec.dot(pvec) * inv;
    if (u < -kBarycentricSlack || u > 1.0 + kBarycentricSlack) continue;
    const Eigen::Vector3d qvec = tvec.cross(e1);
    const double v = d.dot(qvec) * inv;
    if (v < -kBarycentricSlack || u + v > 1.0 + kBarycentricSlack) continue;
    const double r = e2.dot(qvec) * inv;
    if (r <= 0.0 || r > r_max) continue;
    crossings.emplace_back(r, d.dot(body_->normal(t)) > 0.0 ? 1 : -1);
  }
  std::sort(crossings.begin(), crossings.end());
  double begin = 0.0;
  const double same = 1e-10 * radius_;  // crossings closer than this are one (an edge or vertex met twice)
  for (size_t k = 0; k < crossings.size();) {
    size_t e = k;
    int leaving = 0, entering = 0;
    for (; e < crossings.size() && crossings[e].first - crossings[k].first <= same; ++e)
      (crossings[e].second > 0 ? leaving : entering)++;
    const double r = crossings[k].first;
    if (leaving > 0 && entering == 0 && inside) {
      if (r > begin) out->push_back({begin, r});
      inside = false;
    } else if (entering > 0 && leaving == 0 && !inside) {
      begin = r;
      inside = true;
    }
    k = e;
  }
  if (inside && r_max > begin) out->push_back({begin, r_max});
}

}  // namespace meshless::lrpim
