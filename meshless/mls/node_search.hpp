#pragma once
// Nearest-neighbour queries over the EFG node cloud (a nanoflann KD-tree kept out of this header).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {

/// One hit of a radius query.
struct NodeHit {
  int node = -1;           ///< row of the node matrix
  double distance_sq = 0;  ///< |X - X_node|^2 [m^2]
};

/// A KD-tree over the rows of a caller-owned node matrix. The matrix is referenced, never copied: it must
/// outlive this object and must not be moved, resized or edited while the tree exists (build a new
/// NodeSearch after the cloud changes). Queries are const and safe to run from several threads.
class NodeSearch {
 public:
  /// @param nodes #nodes by 3, metres; referenced, not copied
  /// @param leaf_max_size KD-tree leaf size (nanoflann's default 10 is a good trade-off for 3-D queries)
  explicit NodeSearch(const core::PointMatrix& nodes, int leaf_max_size = 10);
  ~NodeSearch();
  NodeSearch(const NodeSearch&) = delete;
  NodeSearch& operator=(const NodeSearch&) = delete;
  NodeSearch(NodeSearch&&) noexcept;
  NodeSearch& operator=(NodeSearch&&) noexcept;

  const core::PointMatrix& nodes() const { return *nodes_; }  ///< #nodes by 3, metres
  int num_nodes() const { return static_cast<int>(nodes_->rows()); }

  /// The min(k, #nodes) nodes closest to X, nearest first (a node at X itself is included).
  /// @param x query point, metres
  /// @param distances_sq if not null, receives the matching squared distances [m^2]
  std::vector<int> nearest(const Eigen::Vector3d& x, int k,
                           std::vector<double>* distances_sq = nullptr) const;

  /// Every node with |X - X_i| < radius (strict), in no particular order. `hits` is cleared first and reused,
  /// so a caller looping over many points can keep one vector and avoid allocations.
  /// @param x query point, metres
  /// @param radius search radius, metres
  void within_radius(const Eigen::Vector3d& x, double radius, std::vector<NodeHit>* hits) const;

  /// Every node i whose own sphere contains X: |X - X_i| < radii[i] (strict). Same traversal as a radius
  /// query of max_radius, but the per-node test runs inside the tree walk so non-covering candidates cost
  /// nothing beyond their distance. `hits` is cleared first, order unspecified.
  /// @param x query point, metres
  /// @param radii #nodes radii, metres
  /// @param max_radius >= radii.maxCoeff(), metres
  void covering(const Eigen::Vector3d& x, const Eigen::VectorXd& radii, double max_radius,
                std::vector<NodeHit>* hits) const;

  /// Convenience form of within_radius(): node ids sorted by increasing distance.
  std::vector<int> within_radius(const Eigen::Vector3d& x, double radius) const;

 private:
  struct Tree;
  const core::PointMatrix* nodes_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace meshless
