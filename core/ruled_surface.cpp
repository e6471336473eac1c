#include "core/ruled_surface.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/surface_query.hpp"

namespace core {
namespace {

constexpr double kMinTraceSegment = 1e-6;        // [m]
const double kMaxTurnCosine = std::cos(M_PI * 160.0 / 180.0);  // sharper turns fold the cut back on itself

/// Closest point of segment [a, b] to p, and its parameter in [0, 1].
Eigen::Vector3d closest_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   double* t_out = nullptr) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  if (t_out) *t_out = t;
  return a + t * ab;
}

/// 2-D orientation of (a, b, c) in the plane spanned by e1, e2.
double orient(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& e1,
              const Eigen::Vector3d& e2) {
  const Eigen::Vector2d u((b - a).dot(e1), (b - a).dot(e2)), v((c - a).dot(e1), (c - a).dot(e2));
  return u.x() * v.y() - u.y() * v.x();
}

bool segments_intersect_2d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& d, const Eigen::Vector3d& e1, const Eigen::Vector3d& e2) {
  const double o1 = orient(a, b, c, e1, e2), o2 = orient(a, b, d, e1, e2);
  const double o3 = orient(c, d, a, e1, e2), o4 = orient(c, d, b, e1, e2);
  if (((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0)) && o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0) return true;
  // Touching or collinear overlap counts as crossing: a cut that meets itself is no simple incision.
  auto on = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    return (closest_on_segment(r, p, q) - r).norm() < kMinTraceSegment;
  };
  return on(a, b, c) || on(a, b, d) || on(c, d, a) || on(c, d, b);
}

}  // namespace

RuledSurface::RuledSurface(std::vector<Eigen::Vector3d> top, const Eigen::Vector3d& direction, double depth,
                           double extension)
    : top_(std::move(top)), direction_(direction.normalized()), depth_(depth), extension_(extension) {
  if (top_.size() < 2) throw std::invalid_argument("the incision needs at least two polyline points");
  if (!(depth_ > 0.0) || !std::isfinite(depth_)) throw std::invalid_argument("the incision's depth must be > 0");
  if (!(extension_ >= 0.0)) throw std::invalid_argument("the incision's extension above the surface must be >= 0");
  if (!direction_.allFinite() || direction.norm() == 0.0)
    throw std::invalid_argument("the incision's depth direction must be a non-zero vector");

  const int n = static_cast<int>(top_.size());
  for (const Eigen::Vector3d& p : top_) {
    trace_.push_back(project(p));
    top_height_.push_back(p.dot(direction_));
  }
  zeta_.push_back(0.0);
  for (int j = 0; j + 1 < n; ++j) {
    const Eigen::Vector3d seg = trace_[j + 1] - trace_[j];
    const double len = seg.norm();
    if (len < kMinTraceSegment)
      throw std::invalid_argument(fmt::format(
          "polyline points {} and {} give a zero-length incision segment (they coincide, or the segment runs along "
          "the depth direction)",
          j, j + 1));
    tangent_.push_back(seg / len);
    normal_.push_back(tangent_.back().cross(direction_).normalized());
    zeta_.push_back(zeta_.back() + len);
  }
  for (int j = 0; j + 2 < n; ++j)
    if (tangent_[j].dot(tangent_[j + 1]) < kMaxTurnCosine)
      throw std::invalid_argument(
          fmt::format("the incision turns back on itself at polyline point {} (a turn sharper than 160 degrees)", j + 1));
  const Eigen::Vector3d e1 = tangent_[0], e2 = direction_.cross(e1);
  for (int i = 0; i + 1 < n; ++i)
    for (int j = i + 2; j + 1 < n; ++j)
      if (segments_intersect_2d(trace_[i], trace_[i + 1], trace_[j], trace_[j + 1], e1, e2))
        throw std::invalid_argument(
            fmt::format("the incision crosses itself: segments {}-{} and {}-{} of the polyline meet (seen along the "
                        "depth direction)",
                        i, i + 1, j, j + 1));
  // The rays that extend the trace beyond its ends (the enrichment's signed distance is taken to the extended
  // trace) must not cross it either.
  {
    const double reach = 1e3 * zeta_.back() + 1.0;  // [m] far beyond the body
    const Eigen::Vector3d start_far = trace_[0] - reach * tangent_[0];
    const Eigen::Vector3d end_far = trace_[n - 1] + reach * tangent_[n - 2];
    for (int j = 0; j + 1 < n; ++j) {
      if (j >= 1 && segments_intersect_2d(trace_[0], start_far, trace_[j], trace_[j + 1], e1, e2))
        throw std::invalid_argument(fmt::format(
            "the incision curls back across the extension of its first segment (at segment {}-{})", j, j + 1));
      if (j + 2 < n && segments_intersect_2d(trace_[n - 1], end_far, trace_[j], trace_[j + 1], e1, e2))
        throw std::invalid_argument(fmt::format(
            "the incision curls back across the extension of its last segment (at segment {}-{})", j, j + 1));
    }
    if (n > 2 && segments_intersect_2d(trace_[0], start_far, trace_[n - 1], end_far, e1, e2))
      throw std::invalid_argument("the extensions of the incision's first and last segments cross");
  }
  // Pseudo-normals at the vertices: at the ends the end segment's normal, at a kink the mean of the two.
  for (int i = 0; i < n; ++i) {
    if (i == 0) vertex_normal_.push_back(normal_.front());
    else if (i == n - 1) vertex_normal_.push_back(normal_.back());
    else vertex_normal_.push_back((normal_[i - 1] + normal_[i]).normalized());
  }
}

Eigen::Vector3d RuledSurface::panel_normal(int panel) const { return normal_.at(panel); }

CutPanel RuledSurface::panel(int i) const {
  CutPanel p;
  p.origin = trace_.at(i);
  p.tangent = tangent_.at(i);
  p.normal = normal_.at(i);
  p.length = zeta_.at(i + 1) - zeta_.at(i);
  p.bottom_start = top_height_.at(i) + depth_;
  p.bottom_end = top_height_.at(i + 1) + depth_;
  return p;
}

CutFrame RuledSurface::frame(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d y = project(x);
  const int last = num_panels() - 1;
  CutFrame f;

  // s: the signed distance to the trace extended by rays beyond both ends (first element wins ties).
  {
    double best = std::numeric_limits<double>::infinity();
    auto consider = [&](double dist2, int segment, double zeta, const Eigen::Vector3d& foot, bool at_kink) {
      if (!(dist2 < best)) return;
      best = dist2;
      f.segment = segment;
      f.zeta = zeta;
      const Eigen::Vector3d r = y - foot;
      if (at_kink) {
        // The outer side of a kink: the distance to the vertex, signed by its pseudo-normal, continuous with the
        // signed distances of both adjacent segments.
        const int vertex = zeta == zeta_[segment] ? segment : segment + 1;
        const double dist = r.norm();
        const double sign = r.dot(vertex_normal_[vertex]) >= 0.0 ? 1.0 : -1.0;
        f.s = sign * dist;
        f.grad_s = dist > 0.0 ? Eigen::Vector3d(sign * r / dist) : vertex_normal_[vertex];
      } else {
        f.s = r.dot(normal_[segment]);
        f.grad_s = normal_[segment];
      }
    };
    const double back = (y - trace_[0]).dot(-tangent_[0]);  // the ray before the start
    if (back > 0.0) consider((y - (trace_[0] - back * tangent_[0])).squaredNorm(), 0, -back, trace_[0] - back * tangent_[0], false);
    for (int j = 0; j <= last; ++j) {
      double t;
      const Eigen::Vector3d q = closest_on_segment(y, trace_[j], trace_[j + 1], &t);
      const bool kink = (t <= 0.0 && j > 0) || (t >= 1.0 && j < last);
      consider((y - q).squaredNorm(), j, zeta_[j] + t * (zeta_[j + 1] - zeta_[j]), q, kink);
    }
    const double ahead = (y - trace_.back()).dot(tangent_[last]);  // the ray after the end
    if (ahead > 0.0)
      consider((y - (trace_.back() + ahead * tangent_[last])).squaredNorm(), last, trace_length() + ahead,
               trace_.back() + ahead * tangent_[last], false);
  }
  {
    const int j = f.segment;
    const double tau = std::clamp((f.zeta - zeta_[j]) / (zeta_[j + 1] - zeta_[j]), 0.0, 1.0);
    f.depth = x.dot(direction_) - ((1.0 - tau) * top_height_[j] + tau * top_height_[j + 1]);
  }

  // distance: to the cut surface, a union of panels. In panel j's plane, with coordinates a along its trace segment
  // and z along the depth direction, the panel is the strip 0 <= a <= len below its bottom line
  // z <= H(a) + depth (open upward). Its bottom edge and the outer edges of the first and last panels are the front.
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  for (int j = 0; j <= last; ++j) {
    const double len = zeta_[j + 1] - zeta_[j];
    const double a0 = (y - trace_[j]).dot(tangent_[j]), z0 = x.dot(direction_);
    const double offset = (y - trace_[j]).dot(normal_[j]);
    const double bottom0 = top_height_[j] + depth_, bottom1 = top_height_[j + 1] + depth_;
    double ac = a0, zc = z0;
    bool front = false;
    const bool inside = a0 >= 0.0 && a0 <= len && z0 <= bottom0 + (bottom1 - bottom0) * a0 / len;
    if (!inside) {
      // The nearest of: the bottom edge, the left edge (a = 0, below bottom0), the right edge (a = len, below bottom1).
      double t;
      const Eigen::Vector2d p(a0, z0), b0(0.0, bottom0), b1(len, bottom1);
      const Eigen::Vector2d e = b1 - b0;
      t = std::clamp((p - b0).dot(e) / e.squaredNorm(), 0.0, 1.0);
      Eigen::Vector2d q = b0 + t * e;
      double d2 = (p - q).squaredNorm();
      front = true;
      const Eigen::Vector2d left(0.0, std::min(z0, bottom0)), right(len, std::min(z0, bottom1));
      if ((p - left).squaredNorm() < d2) {
        q = left;
        d2 = (p - left).squaredNorm();
        front = j == 0;  // only the first panel's left edge ends the cut; the others are kinks
      }
      if ((p - right).squaredNorm() < d2) {
        q = right;
        front = j == last;
      }
      ac = q.x();
      zc = q.y();
    }
    const double d2 = offset * offset + (a0 - ac) * (a0 - ac) + (z0 - zc) * (z0 - zc);
    if (d2 < best) {
      best = d2;
      closest = trace_[j] + ac * tangent_[j] + zc * direction_;
      f.behind_front = !front;
    }
  }
  f.distance = std::sqrt(best);
  f.beyond_front = f.behind_front ? 0.0 : std::sqrt(std::max(0.0, best - f.s * f.s));
  if (f.distance > 0.0) f.grad_distance = (x - closest) / f.distance;
  return f;
}

double RuledSurface::front_distance(const Eigen::Vector3d& x, Eigen::Vector3d* grad) const {
  // The front: the bottom edge (the top line moved down by depth) and the two end edges, which run up from the
  // bottom corners without end (the top edge is not a front).
  Eigen::Vector3d best_point = Eigen::Vector3d::Zero();
  double best = std::numeric_limits<double>::infinity();
  auto consider = [&](const Eigen::Vector3d& q) {
    const double d = (x - q).norm();
    if (d < best) {
      best = d;
      best_point = q;
    }
  };
  for (int j = 0; j < num_panels(); ++j)
    consider(closest_on_segment(x, top_[j] + depth_ * direction_, top_[j + 1] + depth_ * direction_));
  for (const Eigen::Vector3d& corner : {top_.front(), top_.back()}) {
    const Eigen::Vector3d bottom = corner + depth_ * direction_;
    const double up = std::max(0.0, (bottom - x).dot(direction_));  // along -direction from the bottom corner
    consider(bottom - up * direction_);
  }
  if (grad) *grad = best > 0.0 ? Eigen::Vector3d((x - best_point) / best) : Eigen::Vector3d::Zero();
  return best;
}

double RuledSurface::distance(const Eigen::Vector3d& x) const {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_panels(); ++i) {
    const Eigen::Vector3d a = top_[i] - extension_ * direction_, b = top_[i + 1] - extension_ * direction_;
    const Eigen::Vector3d c = top_[i + 1] + depth_ * direction_, d = top_[i] + depth_ * direction_;
    best = std::min(best, (closest_point_on_triangle(x, a, b, c) - x).norm());
    best = std::min(best, (closest_point_on_triangle(x, a, c, d) - x).norm());
  }
  return best;
}

bool RuledSurface::segment_crosses(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  constexpr double kOnPlane = 1e-12;  // [m]
  for (int j = 0; j < num_panels(); ++j) {
    double sa = (a - top_[j]).dot(normal_[j]);
    const double sb = (b - top_[j]).dot(normal_[j]);
    if (std::abs(sa) <= kOnPlane) sa = kOnPlane;  // a start on the cut counts as the s > 0 side
    if (!(sa * sb < 0.0)) continue;
    const double t = sa / (sa - sb);
    const Eigen::Vector3d p = a + t * (b - a);
    const double along = (project(p) - trace_[j]).dot(tangent_[j]);
    const double len = zeta_[j + 1] - zeta_[j];
    if (along < -kOnPlane || along > len + kOnPlane) continue;
    const double tau = std::clamp(along / len, 0.0, 1.0);
    const double depth = p.dot(direction_) - ((1.0 - tau) * top_height_[j] + tau * top_height_[j + 1]);
    if (depth <= depth_ + kOnPlane) return true;
  }
  return false;
}

RuledSurface RuledSurface::truncated(double length) const {
  if (!(length > 0.0) || length > trace_length() * (1.0 + 1e-12))
    throw std::invalid_argument(
        fmt::format("truncated: length {} m outside (0, {}] m", length, trace_length()));
  std::vector<Eigen::Vector3d> points{top_[0]};
  for (int j = 0; j < num_panels(); ++j) {
    if (length >= zeta_[j + 1] - kMinTraceSegment) {
      points.push_back(top_[j + 1]);
      if (length <= zeta_[j + 1] + kMinTraceSegment) break;
      continue;
    }
    const double tau = (length - zeta_[j]) / (zeta_[j + 1] - zeta_[j]);
    points.push_back(top_[j] + tau * (top_[j + 1] - top_[j]));
    break;
  }
  return RuledSurface(points, direction_, depth_, extension_);
}

void RuledSurface::triangulate(PointMatrix* vertices, TriMatrix* triangles) const {
  const int n = static_cast<int>(top_.size());
  vertices->resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    vertices->row(i) = (top_[i] - extension_ * direction_).transpose();
    vertices->row(n + i) = (top_[i] + depth_ * direction_).transpose();
  }
  triangles->resize(2 * num_panels(), 3);
  for (int i = 0; i < num_panels(); ++i) {
    triangles->row(2 * i) << i, i + 1, n + i + 1;
    triangles->row(2 * i + 1) << i, n + i + 1, n + i;
  }
}

double RuledSurface::area() const {
  double s = 0.0;
  for (int i = 0; i < num_panels(); ++i) s += (zeta_[i + 1] - zeta_[i]) * depth_;
  return s;
}

}  // namespace core
