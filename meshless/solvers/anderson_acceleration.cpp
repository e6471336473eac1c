#include "meshless/solvers/anderson_acceleration.hpp"

#include <stdexcept>

namespace meshless {

AndersonAcceleration::AndersonAcceleration(int depth) : depth_(depth) {
  if (depth < 0) throw std::invalid_argument("AndersonAcceleration: depth must be >= 0");
}

void AndersonAcceleration::reset() {
  last_u_.resize(0);
  last_f_.resize(0);
  du_.clear();
  df_.clear();
}

void AndersonAcceleration::start_sequence() {
  last_u_.resize(0);
  last_f_.resize(0);
}

Eigen::VectorXd AndersonAcceleration::next_update(const Eigen::VectorXd& u, const Eigen::VectorXd& f) {
  if (u.size() != f.size()) throw std::invalid_argument("AndersonAcceleration: u and f differ in size");
  if (depth_ == 0) return f;
  if (last_u_.size() == u.size()) {
    du_.push_back(u - last_u_);
    df_.push_back(f - last_f_);
    if (static_cast<int>(du_.size()) > depth_) {
      du_.pop_front();
      df_.pop_front();
    }
  } else if (!du_.empty() && du_.back().size() != u.size()) {
    du_.clear();
    df_.clear();
  }
  last_u_ = u;
  last_f_ = f;
  if (du_.empty()) return f;

  const int m = static_cast<int>(df_.size());
  Eigen::MatrixXd dF(f.size(), m);
  for (int j = 0; j < m; ++j) dF.col(j) = df_[j];
  // Rank-revealing: two nearly parallel updates (a step that barely moved) must not blow gamma up.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(dF);
  qr.setThreshold(1e-10);
  const Eigen::VectorXd gamma = qr.solve(f);
  Eigen::VectorXd update = f;
  for (int j = 0; j < m; ++j) update -= gamma[j] * (du_[j] + df_[j]);
  return update;
}

}  // namespace meshless
