#include "core/json_reader.hpp"

#include <fmt/format.h>

#include <cmath>

namespace core {

std::string describe_json(const nlohmann::json& v) {
  std::string text = v.dump();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return fmt::format("{} {}", v.type_name(), text);
}

JsonReader::JsonReader(std::string file, const nlohmann::json& node, std::string path)
    : file_(std::move(file)), node_(&node), path_(std::move(path)) {
  if (!node_->is_object())
    throw CaseError(file_, path_, "expected a JSON object, got " + describe_json(*node_));
}

void JsonReader::fail(const std::string& key, const std::string& expected) const {
  throw CaseError(file_, key.empty() ? path_ : path_of(key), expected);
}

bool JsonReader::has(const std::string& key) const { return node_->contains(key); }

const nlohmann::json& JsonReader::value(const std::string& key) const {
  used_.insert(key);
  auto it = node_->find(key);
  if (it == node_->end()) fail(key, "required key is missing");
  return *it;
}

const nlohmann::json& JsonReader::array(const std::string& key, int min_count, const std::string& expected) const {
  const nlohmann::json& v = value(key);
  if (!v.is_array() || static_cast<int>(v.size()) < min_count) fail(key, expected);
  return v;
}

JsonReader JsonReader::object(const std::string& key) const {
  return JsonReader(file_, value(key), path_of(key));
}

std::optional<JsonReader> JsonReader::optional_object(const std::string& key) const {
  if (!has(key) || (*node_)[key].is_null()) {
    used_.insert(key);
    return std::nullopt;
  }
  return object(key);
}

double JsonReader::number_at(const nlohmann::json& v, const std::string& path) const {
  if (!v.is_number()) throw CaseError(file_, path, "expected a number, got " + describe_json(v));
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw CaseError(file_, path, "expected a finite number");
  return x;
}

double JsonReader::number(const std::string& key) const { return number_at(value(key), path_of(key)); }

double JsonReader::number(const std::string& key, double fallback) const {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return number(key);
}

double JsonReader::in_range(const std::string& key, double lo, double hi, bool lo_inclusive,
                            bool hi_inclusive, std::optional<double> fallback) const {
  if (!has(key) && fallback) {
    used_.insert(key);
    return *fallback;
  }
  const double x = number(key);
  const bool lo_ok = lo_inclusive ? x >= lo : x > lo;
  const bool hi_ok = hi_inclusive ? x <= hi : x < hi;
  if (!lo_ok || !hi_ok) {
    std::string range = fmt::format("{}{}, {}{}", lo_inclusive ? "[" : "(", lo, hi, hi_inclusive ? "]" : ")");
    if (std::isinf(hi)) range = fmt::format("{} {}", lo_inclusive ? ">=" : ">", lo);
    fail(key, fmt::format("expected a number {}{}, got {}", std::isinf(hi) ? "" : "in ", range, x));
  }
  return x;
}

double JsonReader::positive(const std::string& key) const {
  return in_range(key, 0.0, INFINITY, false, false);
}

double JsonReader::positive(const std::string& key, double fallback) const {
  return in_range(key, 0.0, INFINITY, false, false, fallback);
}

int JsonReader::integer(const std::string& key, int lo, int hi, std::optional<int> fallback) const {
  if (!has(key) && fallback) {
    used_.insert(key);
    return *fallback;
  }
  const nlohmann::json& v = value(key);
  if (!v.is_number_integer())
    fail(key, "expected an integer, got " + describe_json(v));
  const long long x = v.get<long long>();
  if (x < lo || x > hi) fail(key, fmt::format("expected an integer in [{}, {}], got {}", lo, hi, x));
  return static_cast<int>(x);
}

bool JsonReader::boolean(const std::string& key, std::optional<bool> fallback) const {
  if (!has(key) && fallback) {
    used_.insert(key);
    return *fallback;
  }
  const nlohmann::json& v = value(key);
  if (!v.is_boolean()) fail(key, "expected true or false, got " + describe_json(v));
  return v.get<bool>();
}

std::string JsonReader::string(const std::string& key, std::optional<std::string> fallback) const {
  if (!has(key) && fallback) {
    used_.insert(key);
    return *fallback;
  }
  const nlohmann::json& v = value(key);
  if (!v.is_string()) fail(key, "expected a string, got " + describe_json(v));
  return v.get<std::string>();
}

std::string JsonReader::choice(const std::string& key, const std::vector<std::string>& allowed,
                               std::optional<std::string> fallback) const {
  const std::string s = string(key, fallback);
  for (const auto& a : allowed)
    if (s == a) return s;
  fail(key, fmt::format("expected one of \"{}\", got \"{}\"", fmt::join(allowed, "\", \""), s));
}

static Eigen::Vector3d read_vector3(const JsonReader& r, const nlohmann::json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 3)
    throw CaseError(r.file(), path, "expected an array of 3 numbers [x, y, z], got " + describe_json(v));
  Eigen::Vector3d x;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
      throw CaseError(r.file(), path + "/" + std::to_string(i),
                      "expected a finite number, got " + describe_json(v[i]));
    x[i] = v[i].get<double>();
  }
  return x;
}

Eigen::Vector3d JsonReader::vector3(const std::string& key) const {
  return read_vector3(*this, value(key), path_of(key));
}

Eigen::Vector3d JsonReader::vector3(const std::string& key, const Eigen::Vector3d& fallback) const {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return vector3(key);
}

std::vector<Eigen::Vector3d> JsonReader::vector3_list(const std::string& key, int min_count) const {
  const nlohmann::json& v = value(key);
  if (!v.is_array() || static_cast<int>(v.size()) < min_count)
    fail(key, fmt::format("expected an array of at least {} points [x, y, z], got {}", min_count,
                          describe_json(v)));
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < v.size(); ++i)
    out.push_back(read_vector3(*this, v[i], path_of(key) + "/" + std::to_string(i)));
  return out;
}

void JsonReader::finish() const {
  for (auto it = node_->begin(); it != node_->end(); ++it) {
    if (used_.count(it.key())) continue;
    std::vector<std::string> known(used_.begin(), used_.end());
    fail(it.key(), fmt::format("unknown key; allowed keys here are: {}", fmt::join(known, ", ")));
  }
}

}  // namespace core
