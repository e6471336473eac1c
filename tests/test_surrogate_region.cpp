// The surrogate's contact region (meshless/surrogate/contact_region.hpp, region_field.hpp; docs/SURROGATE.md §4):
// the choice of the trained and held-out nodes, the thin-plate-spline weights of eqs. 25-27 in the contact
// position, and eq. 28 over the region with the position as a variable, its contact terms centred on the queried
// point. Synthetic fields with random coefficients, so every check is exact up to rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <random>

#include "meshless/surrogate/contact_region.hpp"
#include "meshless/surrogate/region_field.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace meshless {
namespace {

constexpr double kMm = 1e-3;

/// A curved surface patch: nodes on a sphere of radius 80 mm, within 60 degrees of its north pole, on a
/// jittered grid (so no three contacts are accidentally collinear).
SurfaceNodes sphere_cap() {
  SurfaceNodes s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<Eigen::Vector3d> x;
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j) {
      const double u = (i + jitter(rng)) * 5 * kMm, v = (j + jitter(rng)) * 5 * kMm;
      const double r = 80 * kMm;
      if (u * u + v * v > 0.75 * r * r) continue;
      x.emplace_back(u, v, std::sqrt(r * r - u * u - v * v));
    }
  s.position.resize(static_cast<Eigen::Index>(x.size()), 3);
  s.normal.resize(s.position.rows(), 3);
  for (std::size_t k = 0; k < x.size(); ++k) {
    s.vertex.push_back(static_cast<int>(k));
    s.position.row(k) = x[k].transpose();
    s.normal.row(k) = x[k].normalized().transpose();
  }
  return s;
}

/// A fit with random coefficients at surface node `node`, in that node's own frame. `rng` draws them.
ContactFit random_fit(const SurfaceNodes& s, int node, std::mt19937& rng, bool polynomial_terms = true) {
  std::normal_distribution<double> normal(0.0, 1.0);
  ContactFit c;
  c.contact = node;
  c.frame = SurfaceFrame::at(s.position.row(node).transpose(), s.normal.row(node).transpose(), 0.1, 20 * kMm);
  for (AxisFit& a : c.axis) {
    a.force_order = 3;
    a.contact = Eigen::Matrix3Xd::NullaryExpr(3, 3, [&] { return 1e-3 * normal(rng); });
    a.field_order = 2;
    for (InducedFieldFit& f : a.field) {
      f.tangential_order = 2;
      f.normal_order = 1;
      f.contact_order = 2;
      const SpatialBasis basis(2, 1, 2, c.frame.contact_length / c.frame.length);
      f.coefficients = Eigen::MatrixXd::NullaryExpr(basis.size(), 2, [&] { return 1e-3 * normal(rng); });
      if (!polynomial_terms)
        for (int k = 0; k < basis.size(); ++k)
          if (basis.terms()[k].m == 0) f.coefficients.row(k).setZero();
    }
  }
  return c;
}

SurrogateData data_of(const SurfaceNodes& s, std::vector<ContactFit> contacts, std::optional<ContactRegion> region) {
  SurrogateData d;
  d.case_name = "sphere cap";
  d.case_hash = "0";
  d.max_force = 1.0;
  d.levels = {-1.0, -0.5, 0.5, 1.0};
  d.patch_radius = 6 * kMm;
  d.response_time = "end_of_ramp";
  d.response_seconds = 1.0;
  d.surface_vertex = s.vertex;
  d.surface_position = s.position;
  d.contacts = std::move(contacts);
  d.region = region;
  return d;
}

ContactRegion region_at(const SurfaceNodes& s, int centre, double radius) {
  ContactRegion g;
  g.centre = s.position.row(centre).transpose();
  g.normal = s.normal.row(centre).transpose();
  g.radius = radius;
  return g;
}

TEST(ContactRegion, FarthestPointSamplingSpreadsTheTrainedContactsAndHoldsOutTheFarthestNodes) {
  const SurfaceNodes s = sphere_cap();
  const Eigen::Vector3d centre(1 * kMm, -1 * kMm, 80 * kMm);
  const RegionContacts r = select_region_contacts(s, centre, 20 * kMm, 7, 4);
  ASSERT_EQ(r.training.size(), 7u);
  ASSERT_EQ(r.holdout.size(), 4u);
  EXPECT_EQ(r.training.front(), r.centre_node);
  EXPECT_EQ(r.centre_node, s.nearest(centre));
  const Eigen::Vector3d c = s.position.row(r.centre_node).transpose();
  int inside = 0;
  for (int k = 0; k < s.size(); ++k) inside += (s.position.row(k).transpose() - c).norm() <= 20 * kMm;
  EXPECT_EQ(r.region_nodes, inside);
  auto distance_to_trained = [&](int node) {
    double d = 1e9;
    for (int t : r.training) d = std::min(d, (s.position.row(node) - s.position.row(t)).norm());
    return d;
  };
  for (int t : r.training) EXPECT_LE((s.position.row(t).transpose() - c).norm(), 20 * kMm);
  // The six contacts after the centre lie on the rim (farthest-point sampling reaches the hull first).
  for (std::size_t k = 1; k < r.training.size(); ++k)
    EXPECT_GE((s.position.row(r.training[k]).transpose() - c).norm(), 14 * kMm) << k;
  // Held-out nodes are untrained region nodes, and none is closer to the trained ones than any other
  // untrained node left after them.
  for (int h : r.holdout) {
    EXPECT_EQ(std::count(r.training.begin(), r.training.end(), h), 0);
    EXPECT_LE((s.position.row(h).transpose() - c).norm(), 20 * kMm);
  }
  double smallest_held_out = 1e9;
  for (int h : r.holdout) smallest_held_out = std::min(smallest_held_out, distance_to_trained(h));
  for (int k = 0; k < s.size(); ++k) {
    const bool chosen = std::count(r.training.begin(), r.training.end(), k) ||
                        std::count(r.holdout.begin(), r.holdout.end(), k);
    if (!chosen && (s.position.row(k).transpose() - c).norm() <= 20 * kMm)
      EXPECT_LE(distance_to_trained(k), smallest_held_out + 1e-15);
  }
}

TEST(ContactRegion, TooSmallARegionIsRefusedWithWhatToChange) {
  const SurfaceNodes s = sphere_cap();
  try {
    select_region_contacts(s, {0, 0, 80 * kMm}, 6 * kMm, 7, 4);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("holds"), std::string::npos) << m;
    EXPECT_NE(m.find("/surrogate/contact_region/radius"), std::string::npos) << m;
  }
}

TEST(ContactRegion, ThinPlateWeightsInterpolateSumToOneAndReproduceLinearFunctions) {
  const SurfaceNodes s = sphere_cap();
  const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, 7, 0);
  const ContactRegion g = region_at(s, r.centre_node, 20 * kMm);
  std::vector<Eigen::Vector3d> p;
  for (int t : r.training) p.push_back(s.position.row(t).transpose());
  const ContactInterpolation interpolation(g, p);
  std::vector<double> w(p.size());
  double worst_delta = 0.0;
  for (std::size_t c = 0; c < p.size(); ++c) {
    interpolation.weights(p[c], w.data());
    for (std::size_t d = 0; d < p.size(); ++d) worst_delta = std::max(worst_delta, std::abs(w[d] - (c == d)));
  }
  EXPECT_LE(worst_delta, 1e-14);
  // Anywhere in the region: sum w = 1 and sum w p_c = p in the region's plane (linear precision).
  const Eigen::Vector3d n = g.normal.normalized();
  double worst_sum = 0.0, worst_linear = 0.0;
  for (int k = 0; k < s.size(); ++k) {
    const Eigen::Vector3d x = s.position.row(k).transpose();
    if (!g.contains(x)) continue;
    interpolation.weights(x, w.data());
    double sum = 0.0;
    Eigen::Vector3d combination = Eigen::Vector3d::Zero();
    for (std::size_t c = 0; c < p.size(); ++c) {
      sum += w[c];
      combination += w[c] * p[c];
    }
    const Eigen::Vector3d in_plane_error = (combination - x) - (combination - x).dot(n) * n;
    worst_sum = std::max(worst_sum, std::abs(sum - 1.0));
    worst_linear = std::max(worst_linear, in_plane_error.norm());
  }
  EXPECT_LE(worst_sum, 1e-14);
  std::cout << "delta " << worst_delta << ", sum " << worst_sum << ", linear " << worst_linear << " m\n";
  EXPECT_LE(worst_linear, 1e-16);  // [m]: 5e-15 of the region's 20 mm
}

TEST(ContactRegion, CollinearContactsAreRefused) {
  ContactRegion g;
  g.radius = 10 * kMm;
  EXPECT_THROW(ContactInterpolation(g, {{0, 0, 0}, {1 * kMm, 0, 0}, {2 * kMm, 0, 0}, {3 * kMm, 0, 0}}),
               std::invalid_argument);
}

/// A random field of the region's form, in the frame fit_region_field() builds for this region and these options.
RegionField random_region_field(const SurfaceNodes& s, const ContactRegion& g, int position_order, std::mt19937& rng,
                                double contact_length) {
  std::normal_distribution<double> normal(0.0, 1.0);
  RegionField r;
  double length = 0.0;
  for (int k = 0; k < s.size(); ++k) length = std::max(length, (s.position.row(k).transpose() - g.centre).norm());
  r.frame = SurfaceFrame::at(g.centre, g.normal, length, contact_length);
  r.radius = g.radius;
  r.position_order = position_order;
  for (int j = 0; j < 3; ++j) {
    RegionAxisField& a = r.axis[j];
    a.field_order = 2;
    for (InducedFieldFit& f : a.field) {
      // The axes' contact orders differ (0, 1, 2), as fitted ones do: a component's contact terms then have as
      // many rows as its largest order, zero for the axes with fewer.
      f.tangential_order = 2;
      f.normal_order = 1;
      f.contact_order = j;
      const SpatialBasis basis(2, 1, j, contact_length / length);
      f.coefficients = Eigen::MatrixXd::NullaryExpr(basis.size() * position_monomials(position_order), 2,
                                                    [&] { return 1e-3 * normal(rng); });
    }
  }
  return r;
}

/// The region's eq. 28 fitted on data that a field of its own form produced, at 7 or 10 contacts and 4 levels, is that
/// field everywhere in the region: at untrained nodes and between nodes, where its contact terms sit at the
/// queried point. So the fit, the position monomials and the transported contact terms agree with each other.
TEST(ContactRegion, TheRegionsFieldRecoversAFieldOfItsFormAtUntrainedContacts) {
  const SurfaceNodes s = sphere_cap();
  std::mt19937 rng(11);
  SurrogateFitOptions options;
  options.contact_length = 20 * kMm;
  for (int position_order : {1, 2}) {
    // Degree 2 needs contacts inside the rim as well: the centre and six rim nodes (what 7 contacts give) leave
    // a quadratic of the position undetermined (8.8 % off at untrained nodes here); 10 determine it.
    const int contacts = position_order == 1 ? 7 : 10;
    const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, contacts, 3);
    const ContactRegion g = region_at(s, r.centre_node, 20 * kMm);
    const RegionField truth = random_region_field(s, g, position_order, rng, options.contact_length);
    const RegionFieldEvaluator exact(truth, s.position);
    std::vector<ContactTrainingData> data;
    core::PointMatrix u(s.size(), 3);
    for (int c : r.training) {
      ContactTrainingData d;
      d.contact = c;
      d.levels = {-1.0, -0.5, 0.5, 1.0};
      for (int j = 0; j < 3; ++j)
        for (double level : d.levels) {
          Eigen::Vector3d force = Eigen::Vector3d::Zero();
          force[j] = level;
          exact.evaluate(s.position.row(c).transpose(), force, u.data());
          d.displacement[j].push_back(u);
        }
      data.push_back(std::move(d));
    }
    std::array<RegionAxisField, 3> shape = truth.axis;
    const RegionField fitted = fit_region_field(s, g, data, 1.0, shape, position_order, options);
    const RegionFieldEvaluator recovered(fitted, s.position);
    EXPECT_LE(fitted.training_rms, 1e-15) << "position order " << position_order;
    std::vector<Eigen::Vector3d> queries;
    for (int h : r.holdout) queries.push_back(s.position.row(h).transpose());
    queries.emplace_back(3.3 * kMm, -2.1 * kMm, std::sqrt(6400.0 - 3.3 * 3.3 - 2.1 * 2.1) * kMm);  // between nodes
    core::PointMatrix a(s.size(), 3), b(s.size(), 3);
    const Eigen::Vector3d force(-0.4, 0.2, 0.9);
    double worst = 0.0, scale = 0.0;
    for (const Eigen::Vector3d& p : queries) {
      exact.evaluate(p, force, a.data());
      recovered.evaluate(p, force, b.data());
      worst = std::max(worst, (a - b).cwiseAbs().maxCoeff());
      scale = std::max(scale, a.cwiseAbs().maxCoeff());
    }
    std::cout << "position order " << position_order << ": largest difference " << worst / scale
              << " of the largest displacement\n";
    EXPECT_LE(worst, 1e-9 * scale) << "position order " << position_order;
  }
}

/// Between the trained contacts the dent moves with the query point: a field whose only terms are contact terms
/// with coefficients independent of the position is, at any p, that dent centred on p.
TEST(ContactRegion, TheDentIsCentredOnTheQueryPoint) {
  const SurfaceNodes s = sphere_cap();
  const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, 7, 3);
  const ContactRegion g = region_at(s, r.centre_node, 20 * kMm);
  std::mt19937 rng(13);
  RegionField field = random_region_field(s, g, 0, rng, 20 * kMm);
  for (RegionAxisField& a : field.axis)
    for (InducedFieldFit& f : a.field) {
      const SpatialBasis basis(f.tangential_order, f.normal_order, f.contact_order,
                               field.frame.contact_length / field.frame.length);
      for (int k = 0; k < basis.size(); ++k)
        if (basis.terms()[k].m == 0) f.coefficients.row(k).setZero();
    }
  const RegionFieldEvaluator evaluator(field, s.position);
  core::PointMatrix u(s.size(), 3);
  const Eigen::Vector3d force(-0.4, 0.2, 0.9);
  for (int h : r.holdout) {
    const Eigen::Vector3d p = s.position.row(h).transpose();
    evaluator.evaluate(p, force, u.data());
    // The same coefficients as a contact fit whose frame (same axes) sits at p.
    SurfaceFrame at_p = field.frame;
    at_p.origin = p;
    Eigen::VectorXd expected = Eigen::VectorXd::Zero(3 * s.size());
    for (int j = 0; j < 3; ++j) {
      AxisFit axis;
      axis.field_order = field.axis[j].field_order;
      axis.field = field.axis[j].field;
      const Eigen::MatrixXd n = nodal_coefficients(s, at_p, axis);
      for (int q = 0; q < axis.field_order; ++q) expected += n.col(q) * std::pow(force[j], q + 1);
    }
    const Eigen::Map<const Eigen::VectorXd> got(u.data(), 3 * s.size());
    EXPECT_LE((got - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  }
}

/// A surrogate of the region: random per-contact fits (eqs. 25-27, and eq. 28 for queries outside the region)
/// and a random region field.
SurrogateData region_surrogate(const SurfaceNodes& s, const RegionContacts& r, std::mt19937& rng) {
  std::vector<ContactFit> fits;
  for (int t : r.training) fits.push_back(random_fit(s, t, rng));
  const ContactRegion g = region_at(s, r.centre_node, 20 * kMm);
  SurrogateData d = data_of(s, fits, g);
  d.region_field = random_region_field(s, g, 1, rng, 20 * kMm);
  return d;
}

TEST(ContactRegion, AQueryAtATrainedContactIsThatContactsOwnFit) {
  const SurfaceNodes s = sphere_cap();
  const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, 7, 0);
  std::mt19937 rng(3);
  const SurrogateData d = region_surrogate(s, r, rng);
  const Surrogate region(d);
  SurrogateData without = d;
  without.region.reset();
  without.region_field.reset();
  const Surrogate nearest(without);
  core::PointMatrix ur, un;
  const Eigen::Vector3d force(0.3, -0.7, 0.5);
  for (int t : r.training) {
    const Eigen::Vector3d x = s.position.row(t).transpose();
    const SurrogateResponse a = region.query(x, force, &ur);
    const SurrogateResponse b = nearest.query(x, force, &un);
    EXPECT_TRUE(a.in_contact_region);
    EXPECT_FALSE(b.in_contact_region);
    EXPECT_EQ(a.contact_node, b.contact_node);
    EXPECT_LE((a.contact_displacement - b.contact_displacement).norm(), 1e-13 * b.contact_displacement.norm());
    EXPECT_EQ((ur.row(t) - a.contact_displacement.transpose()).norm(), 0.0);
    // Eq. 28 too: the region's field plus the interpolated corrections is the contact's own fit there.
    EXPECT_LE((ur - un).cwiseAbs().maxCoeff(), 1e-12 * un.cwiseAbs().maxCoeff());
  }
}

TEST(ContactRegion, QueriesOutsideTheRegionAreFlaggedAndTakeTheNearestContact) {
  const SurfaceNodes s = sphere_cap();
  const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, 5, 0);
  std::mt19937 rng(5);
  const SurrogateData d = region_surrogate(s, r, rng);
  const Surrogate region(d);
  const Surrogate nearest(data_of(s, d.contacts, std::nullopt));
  core::PointMatrix ur, un;
  const Eigen::Vector3d far = Eigen::Vector3d(40, 0, std::sqrt(6400.0 - 1600.0)) * kMm;
  const SurrogateResponse a = region.query(far, {0.1, 0.2, 0.3}, &ur);
  const SurrogateResponse b = nearest.query(far, {0.1, 0.2, 0.3}, &un);
  EXPECT_FALSE(a.in_contact_region);
  EXPECT_FALSE(a.on_trained_contact);
  EXPECT_EQ(a.contact, b.contact);
  EXPECT_EQ((ur - un).cwiseAbs().maxCoeff(), 0.0);
}

TEST(ContactRegion, TheSurrogateFileKeepsTheRegion) {
  const SurfaceNodes s = sphere_cap();
  const RegionContacts r = select_region_contacts(s, {0, 0, 80 * kMm}, 20 * kMm, 5, 0);
  std::mt19937 rng(9);
  SurrogateData d = region_surrogate(s, r, rng);
  for (ContactFit& f : d.contacts) f.summaries.push_back({"eq. 28", "SOLVED", true, 0, 1.0, 0.0, 10, 5, 5});
  const std::string path =
      (std::filesystem::temp_directory_path() / "tissue_region_test.surrogate.json").string();
  write_surrogate(path, d);
  const SurrogateData back = read_surrogate(path, std::nullopt);
  std::filesystem::remove(path);
  ASSERT_TRUE(back.region.has_value());
  EXPECT_EQ(back.region->radius, d.region->radius);
  EXPECT_EQ((back.region->centre - d.region->centre).norm(), 0.0);
  core::PointMatrix u1, u2;
  const Eigen::Vector3d p = Eigen::Vector3d(3 * kMm, 4 * kMm, std::sqrt(6400.0 - 25.0) * kMm);
  EXPECT_EQ(back.region_field->position_order, d.region_field->position_order);
  Surrogate(d).query(p, {0.2, 0.1, -0.3}, &u1);
  Surrogate(back).query(p, {0.2, 0.1, -0.3}, &u2);
  EXPECT_EQ((u1 - u2).cwiseAbs().maxCoeff(), 0.0);  // the file keeps every digit (nlohmann: round-trip doubles)
}

}  // namespace
}  // namespace meshless
