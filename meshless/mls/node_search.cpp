#include "meshless/mls/node_search.hpp"

#include <algorithm>
#include <nanoflann.hpp>
#include <stdexcept>
#include <utility>

namespace meshless {

// Debian 12 ships nanoflann 1.4.x: SearchParams (not SearchParameters), radius in squared L2 units, radius
// results as std::vector<std::pair<IndexType, DistanceType>> with IndexType = Eigen::Index here.
struct NodeSearch::Tree {
  using Adaptor = nanoflann::KDTreeEigenMatrixAdaptor<core::PointMatrix, 3, nanoflann::metric_L2_Simple>;
  Adaptor adaptor;
  Tree(const core::PointMatrix& nodes, int leaf_max_size) : adaptor(3, std::cref(nodes), leaf_max_size) {}
};

NodeSearch::NodeSearch(const core::PointMatrix& nodes, int leaf_max_size) : nodes_(&nodes) {
  if (nodes.rows() == 0) throw std::invalid_argument("NodeSearch: the node cloud is empty");
  if (leaf_max_size < 1) throw std::invalid_argument("NodeSearch: leaf_max_size must be >= 1");
  tree_ = std::make_unique<Tree>(nodes, leaf_max_size);
}

NodeSearch::~NodeSearch() = default;
NodeSearch::NodeSearch(NodeSearch&&) noexcept = default;
NodeSearch& NodeSearch::operator=(NodeSearch&&) noexcept = default;

std::vector<int> NodeSearch::nearest(const Eigen::Vector3d& x, int k,
                                     std::vector<double>* distances_sq) const {
  const Eigen::Index n = std::min<Eigen::Index>(std::max(k, 0), nodes_->rows());
  std::vector<Eigen::Index> ids(static_cast<size_t>(n));
  std::vector<double> d2(static_cast<size_t>(n));
  std::vector<int> out;
  if (n > 0) {
    const size_t found =
        tree_->adaptor.index->knnSearch(x.data(), static_cast<size_t>(n), ids.data(), d2.data());
    ids.resize(found);
    d2.resize(found);
  }
  out.assign(ids.begin(), ids.end());
  if (distances_sq != nullptr) *distances_sq = std::move(d2);
  return out;
}

void NodeSearch::within_radius(const Eigen::Vector3d& x, double radius, std::vector<NodeHit>* hits) const {
  hits->clear();
  if (!(radius > 0.0)) return;
  // nanoflann clears and refills its own pair vector; keep one per thread so repeated queries do not
  // allocate.
  thread_local std::vector<std::pair<Eigen::Index, double>> pairs;
  const nanoflann::SearchParams params(/*checks_IGNORED_=*/32, /*eps_=*/0.0f, /*sorted_=*/false);
  tree_->adaptor.index->radiusSearch(x.data(), radius * radius, pairs, params);
  hits->reserve(pairs.size());
  for (const auto& [id, d2] : pairs) hits->push_back(NodeHit{static_cast<int>(id), d2});
}

namespace {

/// nanoflann result set (the RadiusResultSet interface) keeping only nodes whose own radius reaches X.
class CoveringResultSet {
 public:
  using DistanceType = double;
  using IndexType = Eigen::Index;
  CoveringResultSet(double max_radius_sq, const Eigen::VectorXd& radii, std::vector<NodeHit>* hits)
      : max_radius_sq_(max_radius_sq), radii_(radii), hits_(hits) {}
  size_t size() const { return hits_->size(); }
  bool full() const { return true; }
  double worstDist() const { return max_radius_sq_; }
  bool addPoint(double dist_sq, Eigen::Index index) {
    const double rho = radii_[index];
    if (dist_sq < rho * rho) hits_->push_back(NodeHit{static_cast<int>(index), dist_sq});
    return true;  // keep searching
  }

 private:
  double max_radius_sq_;
  const Eigen::VectorXd& radii_;
  std::vector<NodeHit>* hits_;
};

}  // namespace

void NodeSearch::covering(const Eigen::Vector3d& x, const Eigen::VectorXd& radii, double max_radius,
                          std::vector<NodeHit>* hits) const {
  hits->clear();
  if (radii.size() != nodes_->rows())
    throw std::invalid_argument("NodeSearch::covering: one radius per node expected");
  if (!(max_radius > 0.0)) return;
  CoveringResultSet result(max_radius * max_radius, radii, hits);
  tree_->adaptor.index->radiusSearchCustomCallback(x.data(), result,
                                                   nanoflann::SearchParams(32, 0.0f, false));
}

std::vector<int> NodeSearch::within_radius(const Eigen::Vector3d& x, double radius) const {
  std::vector<NodeHit> hits;
  within_radius(x, radius, &hits);
  std::sort(hits.begin(), hits.end(), [](const NodeHit& a, const NodeHit& b) {
    return a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.node < b.node);
  });
  std::vector<int> out(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) out[i] = hits[i].node;
  return out;
}

}  // namespace meshless
