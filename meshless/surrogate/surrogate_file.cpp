#include "meshless/surrogate/surrogate_file.hpp"

#include <fmt/format.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace meshless {
namespace {

using nlohmann::json;

const char* const kFormatName = "tissue-surrogate";
const char* const kAxisName[3] = {"x", "y", "z"};

/// The units every number of the file is in; a reader of another build refuses other units.
json units() { return {{"length", "m"}, {"force", "N"}, {"displacement", "m"}, {"coefficient", "m/N^p"}}; }

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 (OpenSSL EVP_Digest) failed");
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) hex += fmt::format("{:02x}", digest[i]);
  return hex;
}

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }
Eigen::Vector3d vec(const json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}

/// Row-major nested arrays.
json matrix(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    json row = json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}
Eigen::MatrixXd matrix(const json& j, Eigen::Index rows, Eigen::Index cols) {
  if (!j.is_array() || static_cast<Eigen::Index>(j.size()) != rows)
    throw std::runtime_error(fmt::format("expected a matrix of {} rows", rows));
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    if (static_cast<Eigen::Index>(j[r].size()) != cols)
      throw std::runtime_error(fmt::format("expected {} columns in row {}", cols, r));
    for (Eigen::Index c = 0; c < cols; ++c) m(r, c) = j[r][c].get<double>();
  }
  return m;
}

json scores(const std::vector<CvScore>& v) {
  json a = json::array();
  for (const CvScore& s : v)
    a.push_back({{"lambda", s.force_order},
                 {"a", s.tangential_order},
                 {"b", s.normal_order},
                 {"c", s.contact_order},
                 {"rms", s.rms}});
  return a;
}
std::vector<CvScore> scores(const json& j) {
  std::vector<CvScore> v;
  for (const json& s : j) v.push_back({s.at("lambda"), s.at("a"), s.at("b"), s.at("c"), s.at("rms")});
  return v;
}

json frame_json(const SurfaceFrame& f) {
  return {{"origin", vec(f.origin)},     {"tangent1", vec(f.tangent1)}, {"tangent2", vec(f.tangent2)},
          {"normal", vec(f.normal)},     {"length", f.length},          {"contact_length", f.contact_length}};
}
SurfaceFrame frame_from_json(const json& j) {
  SurfaceFrame f;
  f.origin = vec(j.at("origin"));
  f.tangent1 = vec(j.at("tangent1"));
  f.tangent2 = vec(j.at("tangent2"));
  f.normal = vec(j.at("normal"));
  f.length = j.at("length");
  f.contact_length = j.at("contact_length");
  if (!(f.length > 0.0) || !(f.contact_length > 0.0)) throw std::runtime_error("non-positive frame lengths");
  return f;
}

/// The orders (a, b, c) of an eq. 28 component, checked against the ranges the reader accepts.
void read_orders(const json& j, InducedFieldFit* f) {
  f->tangential_order = j.at("a");
  f->normal_order = j.at("b");
  f->contact_order = j.at("c");
  if (f->tangential_order < 0 || f->tangential_order > 12 || f->normal_order < 0 || f->normal_order > 8 ||
      f->contact_order < 0 || f->contact_order > 6)
    throw std::runtime_error("eq. 28 orders outside their ranges");
}

json region_field_json(const RegionField& r) {
  json axes = json::array();
  for (int j = 0; j < 3; ++j) {
    json fields = json::array();
    for (int i = 0; i < 3; ++i) {
      const InducedFieldFit& f = r.axis[j].field[i];
      fields.push_back({{"component", kAxisName[i]},
                        {"a", f.tangential_order},
                        {"b", f.normal_order},
                        {"c", f.contact_order},
                        {"coefficients", matrix(f.coefficients)}});
    }
    axes.push_back({{"axis", kAxisName[j]}, {"field_lambda", r.axis[j].field_order}, {"induced_field", fields}});
  }
  return {{"frame", frame_json(r.frame)},
          {"radius", r.radius},
          {"position_order", r.position_order},
          {"training_rms", r.training_rms},
          {"axes", axes}};
}
RegionField region_field_from_json(const json& j) {
  RegionField r;
  r.frame = frame_from_json(j.at("frame"));
  r.radius = j.at("radius");
  r.position_order = j.at("position_order");
  if (!(r.radius > 0.0) || r.position_order < 0 || r.position_order > 2)
    throw std::runtime_error("contact_region.field: expected a radius > 0 and a position order in [0, 2]");
  r.training_rms = j.at("training_rms");
  if (j.at("axes").size() != 3) throw std::runtime_error("contact_region.field: expected 3 axes");
  for (int k = 0; k < 3; ++k) {
    const json& a = j.at("axes")[k];
    RegionAxisField& axis = r.axis[k];
    axis.field_order = a.at("field_lambda");
    if (axis.field_order < 1 || axis.field_order > 8) throw std::runtime_error("field lambda outside [1, 8]");
    if (a.at("induced_field").size() != 3) throw std::runtime_error("expected 3 induced-field components");
    for (int i = 0; i < 3; ++i) {
      const json& fj = a.at("induced_field")[i];
      InducedFieldFit& f = axis.field[i];
      read_orders(fj, &f);
      const SpatialBasis basis(f.tangential_order, f.normal_order, f.contact_order,
                               r.frame.contact_length / r.frame.length);
      f.coefficients = matrix(fj.at("coefficients"), basis.size() * position_monomials(r.position_order),
                              axis.field_order);
    }
  }
  return r;
}

json to_json(const ContactFit& c) {
  json axes = json::array();
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = c.axis[j];
    json fields = json::array();
    for (int i = 0; i < 3; ++i) {
      const InducedFieldFit& f = a.field[i];
      fields.push_back({{"component", kAxisName[i]},
                        {"a", f.tangential_order},
                        {"b", f.normal_order},
                        {"c", f.contact_order},
                        {"coefficients", matrix(f.coefficients)},
                        {"cv_rms", f.cv_rms},
                        {"cv_grid", scores(f.grid)}});
    }
    axes.push_back({{"axis", kAxisName[j]},
                    {"lambda", a.force_order},
                    {"contact_coefficients", matrix(a.contact)},
                    {"contact_cv_rms", a.contact_cv_rms},
                    {"lambda_cv", scores(a.force_order_cv)},
                    {"field_lambda", a.field_order},
                    {"field_lambda_cv_rms", a.field_order_cv_rms},
                    {"field_lambda_cv", scores(a.field_order_cv)},
                    {"training_rms", a.training_rms},
                    {"induced_field", fields}});
  }
  // The key keeps its format-1 name: files fitted by Ceres LM hold its summaries there, files fitted by the
  // linear least squares hold theirs, with the rank (docs/SURROGATE.md §5).
  json summaries = json::array();
  for (const FitSummary& s : c.summaries) {
    json one = {{"what", s.what},
                {"termination", s.termination},
                {"usable", s.usable},
                {"iterations", s.iterations},
                {"initial_cost", s.initial_cost},
                {"final_cost", s.final_cost},
                {"residuals", s.num_residuals},
                {"parameters", s.num_parameters}};
    if (s.rank >= 0) one["rank"] = s.rank;
    summaries.push_back(std::move(one));
  }
  return {{"surface_node", c.contact},
          {"frame", frame_json(c.frame)},
          {"axes", axes},
          {"ceres_summaries", summaries}};
}

ContactFit contact_from_json(const json& j) {
  ContactFit c;
  c.contact = j.at("surface_node");
  c.frame = frame_from_json(j.at("frame"));
  if (j.at("axes").size() != 3) throw std::runtime_error("expected 3 axes per contact");
  for (int k = 0; k < 3; ++k) {
    const json& a = j.at("axes")[k];
    AxisFit& axis = c.axis[k];
    axis.force_order = a.at("lambda");
    if (axis.force_order < 1 || axis.force_order > 8) throw std::runtime_error("lambda outside [1, 8]");
    axis.contact = matrix(a.at("contact_coefficients"), 3, axis.force_order);
    axis.contact_cv_rms = a.at("contact_cv_rms");
    axis.force_order_cv = scores(a.at("lambda_cv"));
    axis.field_order = a.at("field_lambda");
    if (axis.field_order < 1 || axis.field_order > 8) throw std::runtime_error("field lambda outside [1, 8]");
    axis.field_order_cv_rms = a.at("field_lambda_cv_rms");
    axis.field_order_cv = scores(a.at("field_lambda_cv"));
    axis.training_rms = a.at("training_rms");
    if (a.at("induced_field").size() != 3) throw std::runtime_error("expected 3 induced-field components");
    for (int i = 0; i < 3; ++i) {
      const json& fj = a.at("induced_field")[i];
      InducedFieldFit& field = axis.field[i];
      read_orders(fj, &field);
      const SpatialBasis basis(field.tangential_order, field.normal_order, field.contact_order,
                               c.frame.contact_length / c.frame.length);
      field.coefficients = matrix(fj.at("coefficients"), basis.size(), axis.field_order);
      field.cv_rms = fj.at("cv_rms");
      field.grid = scores(fj.at("cv_grid"));
    }
  }
  for (const json& s : j.at("ceres_summaries"))
    c.summaries.push_back({s.at("what"), s.at("termination"), s.at("usable"), s.at("iterations"),
                           s.at("initial_cost"), s.at("final_cost"), s.at("residuals"), s.at("parameters"),
                           s.value("rank", -1)});  // no rank in files fitted by Ceres
  return c;
}

json content(const SurrogateData& d) {
  json positions = json::array();
  for (Eigen::Index s = 0; s < d.surface_position.rows(); ++s)
    positions.push_back(vec(Eigen::Vector3d(d.surface_position.row(s).transpose())));
  json contacts = json::array();
  for (const ContactFit& c : d.contacts) contacts.push_back(to_json(c));
  json out = {{"format", kFormatName},
          {"format_version", kSurrogateFormatVersion},
          {"case", {{"name", d.case_name}, {"hash", d.case_hash}}},
          {"units", units()},
          {"training",
           {{"max_force", d.max_force},
            {"levels", d.levels},
            {"patch_radius", d.patch_radius},
            {"patch_profile", d.patch_profile},
            {"response_time", d.response_time},
            {"response_seconds", d.response_seconds}}},
          {"surface", {{"vertex", d.surface_vertex}, {"position", positions}}},
          {"contacts", contacts},
          {"report", d.report}};
  // Optional, so that files without a region (format 1 as first written) read unchanged.
  if (d.region)
    out["contact_region"] = {{"centre", vec(d.region->centre)},
                             {"normal", vec(d.region->normal)},
                             {"radius", d.region->radius},
                             {"field", region_field_json(d.region_field.value())}};
  return out;
}

}  // namespace

std::string surrogate_case_hash(const core::Case& c) {
  json relevant = c.document;
  for (const char* key : {"description", "samples", "fem", "output"}) relevant.erase(key);
  std::string bytes = relevant.dump();  // nlohmann::json objects keep their keys sorted: a canonical form
  if (c.geometry.source == core::GeometrySpec::Source::stl) {
    std::ifstream in(c.geometry.stl_file, std::ios::binary);
    if (!in) throw SurrogateFileError(c.geometry.stl_file, "cannot read the case's STL file to hash it");
    bytes.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return sha256_hex(bytes);
}

void write_surrogate(const std::string& path, const SurrogateData& data) {
  json j = content(data);
  j["checksum"] = sha256_hex(j.dump());
  const std::string text = j.dump() + "\n";
  const std::filesystem::path destination(path);
  const std::filesystem::path folder = destination.has_parent_path() ? destination.parent_path() : ".";
  std::string temporary = (folder / ("." + destination.filename().string() + ".XXXXXX")).string();
  const int fd = mkstemp(temporary.data());
  if (fd < 0)
    throw SurrogateFileError(
        path, fmt::format("cannot create a temporary file in {}: {}", folder.string(), std::strerror(errno)));
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  const bool complete = written == text.size() && ::fsync(fd) == 0;
  const int saved_errno = errno;
  if (::close(fd) != 0 || !complete) {
    std::remove(temporary.c_str());
    throw SurrogateFileError(path, fmt::format("writing failed after {} of {} bytes: {}", written,
                                               text.size(), std::strerror(saved_errno)));
  }
  std::error_code ec;
  std::filesystem::rename(temporary, destination, ec);
  if (ec) {
    std::remove(temporary.c_str());
    throw SurrogateFileError(path, "cannot move the finished file into place: " + ec.message());
  }
}

SurrogateData read_surrogate(const std::string& path, const std::optional<std::string>& expected_case_hash) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw SurrogateFileError(
        path, "cannot open the surrogate file (does it exist? `tissue fit CONFIG --out FILE` writes one)");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw SurrogateFileError(
        path, fmt::format("not a complete surrogate file ({} bytes; truncated, or not written by "
                          "`tissue fit`): {}",
                          text.size(), e.what()));
  }
  try {
    if (!j.is_object() || j.value("format", std::string()) != kFormatName)
      throw SurrogateFileError(path,
                               fmt::format("not a surrogate file: expected \"format\": \"{}\"", kFormatName));
    const int version = j.at("format_version");
    if (version != kSurrogateFormatVersion)
      throw SurrogateFileError(path,
                               fmt::format("format version {}, but this tissue reads version {}; re-run "
                                           "`tissue fit` to write a current file",
                                           version, kSurrogateFormatVersion));
    if (j.at("units") != units())
      throw SurrogateFileError(
          path, fmt::format("units {}, but this tissue reads {}", j.at("units").dump(), units().dump()));
    const std::string checksum = j.at("checksum");
    json body = j;
    body.erase("checksum");
    if (sha256_hex(body.dump()) != checksum)
      throw SurrogateFileError(path,
                               "the content does not match its checksum (the file was edited or corrupted); "
                               "re-run `tissue fit`");
    SurrogateData d;
    d.case_name = j.at("case").at("name");
    d.case_hash = j.at("case").at("hash");
    if (expected_case_hash && *expected_case_hash != d.case_hash)
      throw SurrogateFileError(
          path, fmt::format("fitted for case '{}' with hash {}, but the given case has hash {}: "
                            "the case changed since the fit (or is another case); re-run "
                            "`tissue fit` on it",
                            d.case_name, d.case_hash.substr(0, 12), expected_case_hash->substr(0, 12)));
    const json& t = j.at("training");
    d.max_force = t.at("max_force");
    d.levels = t.at("levels").get<std::vector<double>>();
    d.patch_radius = t.at("patch_radius");
    d.patch_profile = t.value("patch_profile", std::string("uniform"));  // files before the smooth profile
    d.response_time = t.at("response_time");
    d.response_seconds = t.at("response_seconds");
    d.surface_vertex = j.at("surface").at("vertex").get<std::vector<int>>();
    const json& positions = j.at("surface").at("position");
    if (positions.size() != d.surface_vertex.size())
      throw std::runtime_error("surface vertex and position counts differ");
    d.surface_position.resize(static_cast<Eigen::Index>(positions.size()), 3);
    for (std::size_t s = 0; s < positions.size(); ++s)
      d.surface_position.row(s) = vec(positions[s]).transpose();
    for (const json& c : j.at("contacts")) d.contacts.push_back(contact_from_json(c));
    if (j.contains("contact_region")) {
      const json& g = j.at("contact_region");
      ContactRegion region;
      region.centre = vec(g.at("centre"));
      region.normal = vec(g.at("normal"));
      region.radius = g.at("radius");
      if (!(region.radius > 0.0) || !(region.normal.norm() > 0.0))
        throw std::runtime_error("contact_region: expected a radius > 0 and a non-zero normal");
      d.region = region;
      d.region_field = region_field_from_json(g.at("field"));
    }
    d.report = j.at("report");
    return d;
  } catch (const SurrogateFileError&) {
    throw;
  } catch (const std::exception& e) {
    throw SurrogateFileError(path, fmt::format("malformed surrogate file: {}", e.what()));
  }
}

}  // namespace meshless
