#pragma once
// Strict reading of one JSON object: every key must be known, every value of the right type and range.
// Errors are core::CaseError naming the file and the JSON pointer of the offending value.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/case_error.hpp"

namespace core {

class JsonReader {
 public:
  /// @param file  the config file name used in messages
  /// @param node  the JSON object to read (must outlive the reader)
  /// @param path  its JSON pointer ("" for the root)
  JsonReader(std::string file, const nlohmann::json& node, std::string path);

  /// Throws unless the node is an object. Call finish() when done to reject unknown keys.
  bool has(const std::string& key) const;
  JsonReader object(const std::string& key) const;
  std::optional<JsonReader> optional_object(const std::string& key) const;

  double number(const std::string& key) const;
  double number(const std::string& key, double fallback) const;
  /// A number with lo < x (strict) or lo <= x, and x < hi or x <= hi.
  double positive(const std::string& key) const;
  double positive(const std::string& key, double fallback) const;
  double in_range(const std::string& key, double lo, double hi, bool lo_inclusive, bool hi_inclusive,
                  std::optional<double> fallback = std::nullopt) const;
  int integer(const std::string& key, int lo, int hi, std::optional<int> fallback = std::nullopt) const;
  bool boolean(const std::string& key, std::optional<bool> fallback = std::nullopt) const;
  std::string string(const std::string& key, std::optional<std::string> fallback = std::nullopt) const;
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     std::optional<std::string> fallback = std::nullopt) const;
  Eigen::Vector3d vector3(const std::string& key) const;
  Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& fallback) const;
  std::vector<Eigen::Vector3d> vector3_list(const std::string& key, int min_count) const;
  /// An array of at least `min_count` elements, for the caller to read element by element ("/key/i").
  const nlohmann::json& array(const std::string& key, int min_count, const std::string& expected) const;

  /// Reject keys that were never asked for.
  void finish() const;

  [[noreturn]] void fail(const std::string& key, const std::string& expected) const;
  std::string path_of(const std::string& key) const { return path_ + "/" + key; }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

 private:
  const nlohmann::json& value(const std::string& key) const;
  double number_at(const nlohmann::json& v, const std::string& path) const;

  std::string file_;
  const nlohmann::json* node_;
  std::string path_;
  mutable std::set<std::string> used_;
};

/// A short rendering of a JSON value for error messages ("got -3", "got \"abc\"").
std::string describe_json(const nlohmann::json& v);

}  // namespace core
