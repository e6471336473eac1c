#include "experiments/studies/sweep.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "core/case.hpp"
#include "core/case_error.hpp"
#include "core/json_reader.hpp"
#include "experiments/comparator/compare.hpp"
#include "experiments/io/child_process.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"

namespace experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// The runs.csv column of the reference's own RMSE against the extrapolated samples (empty without a mesh study that
/// extrapolated this reference).
const char* const kFemVsExtrapolated = "fem_rmse_vs_extrapolated_mm";

/// That column's value from a compare summary.json.
std::string fem_vs_extrapolated(const json& summary) {
  if (!summary.is_object() || !summary.contains("reference")) return "";
  const json& r = summary["reference"];
  if (!r.is_object() || !r.contains("solved_minus_extrapolated_rms_mm")) return "";
  const json& v = r["solved_minus_extrapolated_rms_mm"];
  return v.is_number() ? fmt::format("{:.9g}", v.get<double>()) : std::string();
}

/// FNV-1a, 64 bits: a stable name for a case document (std::hash is not stable across builds).
std::string fnv1a_hex(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char ch : text) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

/// RFC 6901 escaping of one reference token, for JSON paths in messages.
std::string escape_token(const std::string& token) {
  std::string out;
  for (char ch : token) out += ch == '~' ? "~0" : ch == '/' ? "~1" : std::string(1, ch);
  return out;
}

std::string value_text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

/// Checks that `pointer` is a valid RFC 6901 pointer whose parent exists in `document` (the target itself may
/// be an optional key that the base case leaves out); returns why not, or "".
std::string pointer_problem(const std::string& pointer, const json& document) {
  json::json_pointer p;
  try {
    p = json::json_pointer(pointer);
  } catch (const json::exception& e) {
    return fmt::format("expected an RFC 6901 JSON pointer such as \"/meshless/node_spacing\", got \"{}\"", pointer);
  }
  if (p.empty()) return "expected a pointer to a value inside the case, not the whole case (\"\")";
  const json::json_pointer parent = p.parent_pointer();
  if (!document.contains(parent))
    return fmt::format("{} does not exist in the base case (its parent {} is missing)", pointer,
                       parent.to_string().empty() ? "/" : parent.to_string());
  const json& container = document.at(parent);
  if (container.is_array() && !document.contains(p))
    return fmt::format("{} is past the end of the array {} ({} elements)", pointer, parent.to_string(),
                       container.size());
  if (!container.is_object() && !container.is_array())
    return fmt::format("{} is inside {}, which is a {}, not an object or array", pointer, parent.to_string(),
                       container.type_name());
  return "";
}

/// The case for one combination of values, validated; throws core::CaseError from core::parse_case.
json generate_case(const SweepSpec& spec, const std::vector<std::pair<std::string, json>>& assignments) {
  json doc = spec.base_document;
  for (const auto& [pointer, value] : spec.set) doc[json::json_pointer(pointer)] = value;
  for (const auto& [pointer, value] : assignments) doc[json::json_pointer(pointer)] = value;
  const core::Case c = core::parse_case(doc, spec.base_case_file);
  // The generated case is written elsewhere: an STL path relative to the base case must stay valid, also when the
  // sweep file was named relative to the working directory (the resolved path is then relative too).
  if (c.geometry.source == core::GeometrySpec::Source::stl)
    doc["geometry"]["stl_file"] = fs::absolute(c.geometry.stl_file).lexically_normal().string();
  return doc;
}

/// Write next to `path`, then rename over it: a reader or a crash never sees half a file.
void write_replacing(const std::string& path, const std::string& text) {
  const std::string partial = path + ".partial";
  write_text_file(partial, text);
  fs::rename(partial, path);
}

void write_json_file(const std::string& path, const json& j) { write_replacing(path, j.dump(2) + "\n"); }

}  // namespace

SweepSpec load_sweep(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw core::CaseError(path, "", "cannot open the sweep file (does it exist and is it readable?)");
  json doc;
  try {
    doc = json::parse(in);
  } catch (const json::parse_error& e) {
    throw core::CaseError(path, "", fmt::format("expected valid JSON: {}", e.what()));
  }
  if (!doc.is_object()) throw core::CaseError(path, "", "expected a JSON object, got " + core::describe_json(doc));
  const std::set<std::string> allowed{"name", "description", "base_case", "set", "parameters", "compare", "workers"};
  for (const auto& [key, value] : doc.items())
    if (!allowed.count(key))
      throw core::CaseError(path, "/" + escape_token(key),
                            "unknown key; allowed keys here are: base_case, compare, description, name, parameters, "
                            "set, workers");
  SweepSpec s;
  s.file = path;
  const core::JsonReader r(path, doc, "");
  s.name = r.string("name");
  if (s.name.empty() || s.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.") !=
                            std::string::npos || s.name[0] == '.')
    r.fail("name", fmt::format("expected a folder name of letters, digits, '_', '-' or '.', got \"{}\"", s.name));
  s.description = r.string("description", std::string());
  s.workers = r.integer("workers", 1, 64, 1);
  fs::path base = r.string("base_case");
  if (base.is_relative()) base = fs::path(path).parent_path() / base;
  s.base_case_file = base.lexically_normal().string();
  std::ifstream base_in(s.base_case_file);
  if (!base_in) r.fail("base_case", fmt::format("expected an existing case file, but \"{}\" cannot be opened",
                                                s.base_case_file));
  try {
    s.base_document = json::parse(base_in);
  } catch (const json::parse_error& e) {
    r.fail("base_case", fmt::format("{} is not valid JSON: {}", s.base_case_file, e.what()));
  }

  if (doc.contains("set")) {
    if (!doc["set"].is_object())
      throw core::CaseError(path, "/set", "expected an object of JSON pointer -> value, got " +
                                              core::describe_json(doc["set"]));
    for (const auto& [pointer, value] : doc["set"].items()) {
      const std::string where = "/set/" + escape_token(pointer);
      if (const std::string problem = pointer_problem(pointer, s.base_document); !problem.empty())
        throw core::CaseError(path, where, problem);
      s.set.emplace_back(pointer, value);
    }
  }
  if (doc.contains("compare")) {
    const json& c = doc["compare"];
    if (!c.is_object())
      throw core::CaseError(path, "/compare",
                            "expected an object {\"reference\": \"solved\" or \"extrapolated\", \"reference_error\": "
                            "\"fem.json\"}, got " + core::describe_json(c));
    for (const auto& [key, value] : c.items())
      if (key != "reference" && key != "reference_error")
        throw core::CaseError(path, "/compare/" + escape_token(key),
                              "unknown key; allowed keys here are: reference, reference_error");
    const core::JsonReader cr(path, c, "/compare");
    s.compare.reference = cr.string("reference", std::string());
    if (!s.compare.reference.empty() && s.compare.reference != "solved" && s.compare.reference != "extrapolated")
      cr.fail("reference", fmt::format("expected \"solved\" or \"extrapolated\", got \"{}\"", s.compare.reference));
    if (c.contains("reference_error")) {
      fs::path file = cr.string("reference_error");
      if (file.is_relative()) file = fs::path(path).parent_path() / file;
      // absolute: the runs' compare may start in another folder
      s.compare.reference_error = fs::absolute(file).lexically_normal().string();
      std::ifstream study_in(s.compare.reference_error);
      if (!study_in)
        cr.fail("reference_error", fmt::format("expected an existing `tissue verify fem` result (fem.json), but \"{}\" "
                                               "cannot be opened (the path is relative to the sweep file's folder)",
                                               s.compare.reference_error));
      const json study = json::parse(study_in, nullptr, false);
      if (study.is_discarded() || !study.is_object() || !study.contains("mesh_convergence"))
        cr.fail("reference_error", fmt::format("expected a `tissue verify fem` result with a mesh_convergence study, but "
                                               "{} {}",
                                               s.compare.reference_error,
                                               study.is_discarded() ? "is not valid JSON" : "has no mesh_convergence"));
    } else if (s.compare.reference == "extrapolated") {
      throw core::CaseError(path, "/compare",
                            "\"reference\": \"extrapolated\" needs \"reference_error\": the fem.json of `tissue verify "
                            "fem` whose extrapolated samples stand for the reference");
    }
  }
  if (!doc.contains("parameters") || !doc["parameters"].is_array() || doc["parameters"].empty())
    throw core::CaseError(path, "/parameters",
                          "expected a non-empty array of {\"pointer\": \"/json/pointer\", \"values\": [...]} or "
                          "{\"pointers\": [\"/a\", \"/b\"], \"values\": [[a1, b1], ...]}");
  std::set<std::string> seen;
  // the base document as the runs see it: `set` applied
  json with_set = s.base_document;
  for (const auto& [ptr, value] : s.set) with_set[json::json_pointer(ptr)] = value;
  for (std::size_t i = 0; i < doc["parameters"].size(); ++i) {
    const json& p = doc["parameters"][i];
    const std::string where = fmt::format("/parameters/{}", i);
    if (!p.is_object())
      throw core::CaseError(path, where,
                            "expected an object {\"pointer\": ..., \"values\": [...]} or {\"pointers\": [...], "
                            "\"values\": [[...], ...]}, got " + core::describe_json(p));
    for (const auto& [key, value] : p.items())
      if (key != "pointer" && key != "pointers" && key != "values")
        throw core::CaseError(path, where + "/" + escape_token(key),
                              "unknown key; allowed keys here are: pointer (one), pointers (several, zipped), values");
    const core::JsonReader pr(path, p, where);
    SweepParameter param;
    std::vector<std::string> where_pointer;  // the JSON path of each pointer in the sweep file
    if (p.contains("pointer") && p.contains("pointers"))
      throw core::CaseError(path, where + "/pointers",
                            "expected either \"pointer\" (one) or \"pointers\" (several, zipped), not both");
    if (!p.contains("pointer") && !p.contains("pointers"))
      throw core::CaseError(path, where,
                            "expected \"pointer\" (one JSON pointer) or \"pointers\" (several that vary together), "
                            "beside \"values\"");
    if (p.contains("pointers")) {
      param.zipped = true;
      const json& list = p["pointers"];
      if (!list.is_array() || list.empty())
        throw core::CaseError(path, where + "/pointers",
                              "expected a non-empty array of JSON pointers that vary together, got " +
                                  core::describe_json(list));
      for (std::size_t j = 0; j < list.size(); ++j) {
        if (!list[j].is_string())
          throw core::CaseError(path, fmt::format("{}/pointers/{}", where, j),
                                "expected a JSON pointer string, got " + core::describe_json(list[j]));
        param.pointers.push_back(list[j].get<std::string>());
        where_pointer.push_back(fmt::format("{}/pointers/{}", where, j));
      }
    } else {
      param.pointers.push_back(pr.string("pointer"));
      where_pointer.push_back(where + "/pointer");
    }
    const std::string names = fmt::format("{}", fmt::join(param.pointers, ", "));
    if (!p.contains("values") || !p["values"].is_array() || p["values"].empty())
      pr.fail("values", "expected a non-empty array of values for " + names);
    param.values = p["values"].get<std::vector<json>>();
    (void)pr.has("values");
    if (param.zipped)
      for (std::size_t k = 0; k < param.values.size(); ++k)
        if (!param.values[k].is_array() || param.values[k].size() != param.pointers.size())
          throw core::CaseError(path, fmt::format("{}/values/{}", where, k),
                                fmt::format("expected an array of {} values, one for each of {} (in that order), got {}",
                                            param.pointers.size(), names,
                                            param.values[k].is_array()
                                                ? fmt::format("an array of {}", param.values[k].size())
                                                : core::describe_json(param.values[k])));
    for (std::size_t j = 0; j < param.pointers.size(); ++j) {
      const std::string& pointer = param.pointers[j];
      if (const std::string problem = pointer_problem(pointer, with_set); !problem.empty())
        throw core::CaseError(path, where_pointer[j], problem);
      if (!seen.insert(pointer).second)
        throw core::CaseError(path, where_pointer[j], pointer + " is swept twice; list its values once");
      for (const auto& [ptr, value] : s.set)
        if (ptr == pointer)
          throw core::CaseError(path, where_pointer[j], pointer + " is also in /set; keep it in one place");
    }
    s.parameters.push_back(param);
  }
  return s;
}

std::vector<SweepRun> expand_sweep(const SweepSpec& spec) {
  // The base case with `set` applied must itself be valid.
  try {
    generate_case(spec, {});
  } catch (const core::CaseError& e) {
    throw core::CaseError(spec.file, spec.set.empty() ? "/base_case" : "/set",
                          fmt::format("the base case {} {}is invalid: {}", spec.base_case_file,
                                      spec.set.empty() ? "" : "with /set applied ", e.what()));
  }
  // Each value alone, so that a bad value is named precisely (a zipped parameter's values one pointer at a
  // time, then together).
  for (std::size_t i = 0; i < spec.parameters.size(); ++i)
    for (std::size_t k = 0; k < spec.parameters[i].values.size(); ++k) {
      const auto& param = spec.parameters[i];
      std::vector<std::pair<std::string, json>> together;
      std::string described;
      for (std::size_t j = 0; j < param.pointers.size(); ++j) {
        const std::string& pointer = param.pointers[j];
        const json& v = param.value(k, j);
        together.emplace_back(pointer, v);
        described += fmt::format("{}{} = {}", j ? ", " : "", pointer, value_text(v));
        try {
          generate_case(spec, {{pointer, v}});
        } catch (const core::CaseError& e) {
          throw core::CaseError(spec.file,
                                param.zipped ? fmt::format("/parameters/{}/values/{}/{}", i, k, j)
                                             : fmt::format("/parameters/{}/values/{}", i, k),
                                fmt::format("{} = {} makes an invalid case: {}", pointer, value_text(v), e.what()));
        }
      }
      if (!param.zipped) continue;
      try {
        generate_case(spec, together);
      } catch (const core::CaseError& e) {
        throw core::CaseError(spec.file, fmt::format("/parameters/{}/values/{}", i, k),
                              fmt::format("{} together make an invalid case: {}", described, e.what()));
      }
    }
  // The extrapolated reference exists only at the mesh study's levels: refuse any other mesh size now, not after
  // hours of runs (whether a run's FEM samples equal its level's is checked by its compare, after the FEM solve).
  json study_levels;  // case name -> levels, when the extrapolated reference is asked for
  if (spec.compare.reference == "extrapolated") {
    std::ifstream in(spec.compare.reference_error);
    const json study = json::parse(in, nullptr, false);
    if (!study.is_discarded() && study.contains("mesh_convergence")) study_levels = study["mesh_convergence"];
  }
  const auto check_study_level = [&](const json& document, const std::string& combination) {
    if (spec.compare.reference != "extrapolated") return;
    const core::Case c = core::parse_case(document, spec.base_case_file);
    const std::string file = spec.compare.reference_error;
    if (!study_levels.is_object() || !study_levels.contains(c.name))
      throw core::CaseError(spec.file, "/compare/reference_error",
                            fmt::format("{} holds no mesh study of the case \"{}\" (run {}), so compare would refuse "
                                        "the extrapolated reference; run `tissue verify fem --config {}`",
                                        file, c.name, combination, spec.base_case_file));
    const json& study = study_levels[c.name];
    if (!study.contains("richardson") || !study["richardson"].contains("extrapolated_sample_displacements_mm"))
      throw core::CaseError(spec.file, "/compare/reference_error",
                            fmt::format("the mesh study of {} in {} holds no extrapolated samples "
                                        "(richardson.extrapolated_sample_displacements_mm)",
                                        c.name, file));
    std::string sizes;
    const double mesh_size_mm = c.geometry.mesh_size * 1e3;  // the case holds metres
    for (const auto& level : study.value("levels", json::array())) {
      const double h = level.value("mesh_size_mm", -1.0);
      if (std::abs(h - mesh_size_mm) <= 1e-9) return;  // as compare_metrics.cpp reference_error_bar
      sizes += fmt::format("{}{:g}", sizes.empty() ? "" : ", ", h);
    }
    throw core::CaseError(spec.file, "/compare/reference_error",
                          fmt::format("the run {} has /geometry/mesh_size = {:g} mm, which is not a level of the mesh "
                                      "study of {} in {} (levels {} mm): compare would refuse the extrapolated "
                                      "reference; sweep the mesh size over the study's levels",
                                      combination, mesh_size_mm, c.name, file, sizes));
  };
  const std::vector<std::string> compare_args = spec.compare.arguments();
  std::string compare_key;  // the compare options change the results, so they are part of the run's id
  for (const auto& a : compare_args) compare_key += "\n" + a;
  // The Cartesian product, last parameter fastest.
  const std::vector<std::string> columns = spec.columns();
  std::vector<SweepRun> runs;
  std::vector<std::size_t> index(spec.parameters.size(), 0);
  std::set<std::string> ids;
  while (true) {
    std::vector<std::pair<std::string, json>> assignments;
    SweepRun run;
    for (std::size_t i = 0; i < spec.parameters.size(); ++i)
      for (std::size_t j = 0; j < spec.parameters[i].pointers.size(); ++j) {
        const json& v = spec.parameters[i].value(index[i], j);
        assignments.emplace_back(spec.parameters[i].pointers[j], v);
        run.values.push_back(v);
      }
    std::string combination;
    for (std::size_t c = 0; c < columns.size(); ++c)
      combination += fmt::format("{}{} = {}", c ? ", " : "", columns[c], value_text(run.values[c]));
    try {
      run.document = generate_case(spec, assignments);
    } catch (const core::CaseError& e) {
      throw core::CaseError(spec.file, "/parameters",
                            fmt::format("the combination {} makes an invalid case: {}", combination, e.what()));
    }
    check_study_level(run.document, combination);
    run.id = fnv1a_hex(run.document.dump() + compare_key);
    if (ids.insert(run.id).second) runs.push_back(std::move(run));  // equal values twice: one run
    std::size_t i = spec.parameters.size();
    while (i > 0 && ++index[i - 1] == spec.parameters[i - 1].values.size()) index[--i] = 0;
    if (i == 0) break;
  }
  return runs;
}

std::vector<std::string> SweepCompareOptions::arguments() const {
  std::vector<std::string> args;
  if (!reference.empty()) args.insert(args.end(), {"--reference", reference});
  if (!reference_error.empty()) args.insert(args.end(), {"--reference-error", reference_error});
  return args;
}

std::vector<std::string> SweepSpec::columns() const {
  std::vector<std::string> out;
  for (const auto& p : parameters) out.insert(out.end(), p.pointers.begin(), p.pointers.end());
  return out;
}

std::string csv_field(const std::string& text) {
  std::string t = text;
  std::replace(t.begin(), t.end(), '\n', ' ');
  std::replace(t.begin(), t.end(), '\r', ' ');
  if (t.find_first_of(",\"") == std::string::npos) return t;
  std::string quoted = "\"";
  for (char ch : t) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return quoted + "\"";
}

/// The scored models of every run: the base case's /compare/models (a sweep that changes the list itself still gets
/// the base case's columns; the other models are in each run's summary.json).
std::vector<std::string> scored_models(const SweepSpec& spec) {
  json base = spec.base_document;  // with `set` applied: a sweep may set /compare/models for every run
  for (const auto& [pointer, value] : spec.set) base[json::json_pointer(pointer)] = value;
  const nlohmann::json* list = base.contains("compare") ? &base["compare"] : nullptr;
  if (!list || !list->contains("models")) return core::CompareSpec{}.models;
  std::vector<std::string> names;
  for (const auto& m : (*list)["models"])
    if (m.is_string()) names.push_back(m.get<std::string>());
  return names;
}

std::vector<std::string> runs_csv_header(const SweepSpec& spec) {
  std::vector<std::string> header{"run_id", "status"};
  for (const auto& p : spec.columns()) header.push_back(p);
  for (const auto& c : compare_row_columns(scored_models(spec))) header.push_back(c);
  header.push_back(kFemVsExtrapolated);
  header.push_back("wall_seconds");
  header.push_back("error");
  return header;
}

namespace {

std::string join_row(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + csv_field(fields[i]);
  return line + "\n";
}

/// The first `n` fields of a row written by join_row (the run id and status are never quoted).
std::vector<std::string> leading_fields(const std::string& line, std::size_t n) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (out.size() < n && start <= line.size()) {
    const std::size_t comma = line.find(',', start);
    out.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

/// write(2) the whole buffer, then fsync: a row reaches the disk whole or, after a crash, as a tail without
/// its newline that the next RunsCsv removes.
void append_whole(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(fmt::format("cannot open {} for appending: {}", path, std::strerror(errno)));
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error(fmt::format("appending to {} failed: {}", path, std::strerror(err)));
    }
    done += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  const int err = errno;
  if (::close(fd) != 0 || !synced)
    throw std::runtime_error(fmt::format("appending to {} failed: {}", path, std::strerror(err)));
}

}  // namespace

RunsCsv::RunsCsv(const std::string& path, const std::vector<std::string>& header)
    : path_(path), columns_(header.size()) {
  const std::string expected_header = join_row(header);
  std::string text;
  if (fs::exists(path)) {
    std::ifstream in(path, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) throw std::runtime_error("cannot read " + path);
  }
  if (!text.empty() && text.back() != '\n') {
    // A crash during an append left a row without its newline: drop it (that run reruns).
    const std::size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
    fs::resize_file(path, keep);
    text.resize(keep);
    repaired_ = true;
  }
  if (text.empty()) {
    append_whole(path, expected_header);
    return;
  }
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);
  if (line + "\n" != expected_header)
    throw std::runtime_error(fmt::format("{} has other columns than this sweep ({}): it belongs to another sweep; "
                                         "move it away or choose another --out",
                                         path, line.substr(0, 120)));
  while (std::getline(lines, line)) {
    const auto f = leading_fields(line, 2);
    if (f.size() == 2) rows_.emplace_back(f[0], f[1]);
  }
}

std::string RunsCsv::last_status(const std::string& run_id) const {
  for (auto it = rows_.rbegin(); it != rows_.rend(); ++it)
    if (it->first == run_id) return it->second;
  return "";
}

void RunsCsv::append(const std::vector<std::string>& fields) {
  if (fields.size() != columns_)
    throw std::logic_error(fmt::format("runs.csv row with {} fields, expected {}", fields.size(), columns_));
  append_whole(path_, join_row(fields));
  rows_.emplace_back(fields[0], fields[1]);
}

bool SweepOptions::IsValid(std::string* why) const {
  if (workers < 0) {
    if (why) *why = "--workers must be >= 1";
    return false;
  }
  return true;
}

int sweep_workers(const SweepSpec& spec, const SweepOptions& options) {
  return std::max(1, options.workers > 0 ? options.workers : spec.workers);
}

RunFunction compare_in_child_process(const std::string& tissue_binary, bool plot,
                                     const std::vector<std::string>& compare_arguments, int threads) {
  const std::vector<std::string> environment = threads > 0 ? thread_limit_environment(threads) : std::vector<std::string>();
  return [tissue_binary, plot, compare_arguments, environment](const SweepRun&, const std::string& case_file,
                                                  const std::string& run_dir, const std::string& log_file) {
    RunOutcome outcome;
    std::vector<std::string> argv{tissue_binary, "compare", case_file, "--out", run_dir};
    if (!plot) argv.push_back("--no-plot");
    argv.insert(argv.end(), compare_arguments.begin(), compare_arguments.end());
    const ProcessOutcome p = run_process(argv, log_file, environment);
    if (!p.ok()) {
      outcome.error = child_failure(p, log_file);  // the child's own `error: ...` line, else how it ended
      return outcome;
    }
    std::ifstream in(fs::path(run_dir) / "summary.json");
    outcome.summary = json::parse(in, nullptr, false);
    outcome.ok = !outcome.summary.is_discarded();
    if (!outcome.ok) outcome.error = "the run succeeded but its summary.json cannot be read";
    return outcome;
  };
}

SweepReport run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options,
                      const RunFunction& run_function) {
  const fs::path out = options.out_dir.empty() ? fs::path("results/sweeps") / spec.name : fs::path(options.out_dir);
  const std::vector<std::string> models = scored_models(spec);
  fs::create_directories(out / "cases");
  fs::create_directories(out / "runs");
  fs::create_directories(out / "logs");
  // One sweep per folder at a time: a second one would append the same runs twice.
  const std::string lock_path = (out / ".sweep.lock").string();
  const int lock = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX | LOCK_NB) != 0) {
    if (lock >= 0) ::close(lock);
    throw std::runtime_error(fmt::format("another sweep is running in {} (it holds {})", out.string(), lock_path));
  }
  struct Unlock {
    int fd;
    ~Unlock() { ::close(fd); }
  } unlock{lock};

  RunsCsv csv((out / "runs.csv").string(), runs_csv_header(spec));
  if (csv.repaired())
    std::cerr << fmt::format("[sweep {}] removed a half-written last row from {} (that run reruns)\n", spec.name,
                             (out / "runs.csv").string());
  json copy = {{"sweep_file", spec.file}, {"base_case", spec.base_case_file}, {"name", spec.name}};
  write_json_file((out / "sweep.json").string(), copy);

  SweepReport report;
  report.total = static_cast<int>(runs.size());
  std::vector<const SweepRun*> pending;
  for (const auto& run : runs) {
    const std::string status = csv.last_status(run.id);
    if (status == "ok" || (status == "failed" && !options.retry_failed))
      ++report.skipped;
    else
      pending.push_back(&run);
  }
  const int workers = sweep_workers(spec, options);
  std::cerr << fmt::format("[sweep {}] {} runs: {} already done, {} to run with {} worker(s); rows go to {}\n",
                           spec.name, report.total, report.skipped, pending.size(), workers,
                           (out / "runs.csv").string());
  Progress progress("sweep " + spec.name, static_cast<int>(pending.size()));
  std::mutex mutex;
  std::size_t next = 0;
  const std::vector<std::string> columns = spec.columns();
  const auto describe = [&](const SweepRun& run) {
    std::string s;
    for (std::size_t i = 0; i < columns.size(); ++i)
      s += fmt::format("{}{} = {}", i ? ", " : "", columns[i], value_text(run.values[i]));
    return s;
  };
  std::exception_ptr fatal;  // an append that failed: the record would be wrong, so the sweep stops
  const auto worker = [&]() {
    while (true) {
      const SweepRun* run = nullptr;
      {
        std::lock_guard<std::mutex> guard(mutex);
        if (next == pending.size() || fatal) return;
        run = pending[next++];
        std::cerr << fmt::format("[sweep {}] starting {} ({})\n", spec.name, run->id, describe(*run));
      }
      const std::string case_file = (out / "cases" / (run->id + ".json")).string();
      const std::string run_dir = (out / "runs" / run->id).string();
      const std::string log_file = (out / "logs" / (run->id + ".log")).string();
      const auto t0 = std::chrono::steady_clock::now();
      RunOutcome outcome;
      try {
        write_json_file(case_file, run->document);
        fs::remove(log_file);
        outcome = run_function(*run, case_file, run_dir, log_file);
      } catch (const std::exception& e) {
        outcome.ok = false;
        outcome.error = e.what();
      } catch (...) {
        outcome.ok = false;
        outcome.error = "the run stopped with an exception that is not a std::exception";
      }
      outcome.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      // The row's values, read from the run's summary.json; an unreadable summary fails this run, not the sweep
      // (an exception leaving this thread would end the process).
      std::vector<std::string> values(compare_row_columns(models).size());
      std::string versus_extrapolated;
      if (outcome.ok) {
        try {
          values = compare_row_values(outcome.summary, models);
          versus_extrapolated = fem_vs_extrapolated(outcome.summary);
        } catch (const std::exception& e) {
          outcome.ok = false;
          outcome.error = std::string("its summary.json could not be read as a comparison: ") + e.what();
          values.assign(values.size(), std::string());
        }
      }
      std::replace(outcome.error.begin(), outcome.error.end(), '\n', ' ');  // one line in runs.csv and progress
      std::vector<std::string> row{run->id, outcome.ok ? "ok" : "failed"};
      for (const auto& v : run->values) row.push_back(value_text(v));
      row.insert(row.end(), values.begin(), values.end());
      row.push_back(versus_extrapolated);
      row.push_back(fmt::format("{:.3f}", outcome.wall_seconds));
      row.push_back(outcome.ok ? "" : outcome.error);
      std::lock_guard<std::mutex> guard(mutex);
      try {
        csv.append(row);
      } catch (...) {
        if (!fatal) fatal = std::current_exception();
        return;
      }
      if (outcome.ok) {
        ++report.succeeded;
        const json& m = outcome.summary["models"];
        std::string rmse;
        for (const auto& name : models)
          if (m.contains(name) && m[name]["rmse_mm"].is_number())
            rmse += fmt::format("{}{} {:.4f} mm", rmse.empty() ? "" : ", ", name, m[name]["rmse_mm"].get<double>());
        progress.step(fmt::format("{} ({}): ok, RMSE {}, {:.0f} s", run->id, describe(*run), rmse, outcome.wall_seconds));
      } else {
        ++report.failed;
        progress.step(fmt::format("{} ({}): FAILED: {} (log: {})", run->id, describe(*run), outcome.error, log_file));
      }
    }
  };
  std::vector<std::thread> threads;
  for (int w = 0; w < std::min<int>(workers, static_cast<int>(pending.size())); ++w) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (fatal) std::rethrow_exception(fatal);
  progress.done();
  return report;
}

namespace {

/// The current sweep's results, one row per run in product order (runs.csv is the append-only log; this is
/// the view of the runs this sweep file defines now): summary.csv, summary.md and sweep.png.
void write_sweep_summary(const SweepSpec& spec, const std::vector<SweepRun>& runs, const fs::path& out, bool plot) {
  RunsCsv csv((out / "runs.csv").string(), runs_csv_header(spec));
  std::vector<std::string> header{"run_id", "status"};
  const std::vector<std::string> pointers = spec.columns();
  for (const auto& p : pointers) header.push_back(p);
  const std::vector<std::string> models = scored_models(spec);
  std::vector<std::string> columns = compare_row_columns(models);
  columns.push_back(kFemVsExtrapolated);
  for (const auto& c : columns) header.push_back(c);
  const bool extrapolated = spec.compare.reference == "extrapolated";
  std::string summary_csv = join_row(header);
  std::string md = fmt::format("# Sweep {}\n\n{}{}Produced by `tissue sweep {}` (base case {}). One row per run; "
                               "RMSE of eq. 34 against the {}, times in seconds.\n\n|",
                               spec.name, spec.description, spec.description.empty() ? "" : "\n\n", spec.file,
                               spec.base_case_file,
                               extrapolated ? "extrapolated FEM reference (the samples Richardson-extrapolated by the "
                                              "mesh study " + spec.compare.reference_error + "; the FEM's own RMSE "
                                              "against them is the column \"FEM vs extrapolated\")"
                                            : std::string("FEM reference"));
  for (const auto& p : pointers) md += " " + p + " |";
  md += " status |";
  for (const auto& m : models) md += fmt::format(" RMSE {} [mm] | {} / peak | without flagged, {} [mm] |", m, m, m);
  if (extrapolated) md += " FEM vs extrapolated [mm] |";
  md += " reference [s] |";
  for (const auto& m : models) md += fmt::format(" {} [s] |", m);
  md += " run |\n|";
  for (std::size_t i = 0; i < pointers.size() + 4 * models.size() + 3 + (extrapolated ? 1 : 0); ++i) md += "---|";
  md += "\n";
  for (const auto& run : runs) {
    const std::string status = csv.last_status(run.id);
    std::vector<std::string> row{run.id, status.empty() ? "not run" : status};
    for (const auto& v : run.values) row.push_back(value_text(v));
    std::vector<std::string> values(columns.size());
    json summary;
    if (status == "ok") {
      std::ifstream in(out / "runs" / run.id / "summary.json");
      summary = json::parse(in, nullptr, false);
      if (!summary.is_discarded()) {
        values = compare_row_values(summary, models);
        values.push_back(fem_vs_extrapolated(summary));
      }
    }
    row.insert(row.end(), values.begin(), values.end());
    summary_csv += join_row(row);
    md += "|";
    for (const auto& v : run.values) md += " " + value_text(v) + " |";
    const auto column = [&](const std::string& name) {
      const std::string& v =
          values[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin())];
      return v.empty() ? std::string("–") : fmt::format("{:.4g}", std::stod(v));  // full precision in summary.csv
    };
    md += " " + row[1] + " |";
    for (const auto& m : models)
      md += fmt::format(" {} | {} | {} |", column(m + "_rmse_mm"), column(m + "_rmse_relative"),
                        column(m + "_rmse_unflagged_mm"));
    if (extrapolated) md += " " + column(kFemVsExtrapolated) + " |";
    md += " " + column("fem_seconds") + " |";
    for (const auto& m : models) md += " " + column(m + "_seconds") + " |";
    md += fmt::format(" {} |\n", status == "failed" ? "failed: logs/" + run.id + ".log" : "runs/" + run.id);
  }
  write_replacing((out / "summary.csv").string(), summary_csv);
  write_replacing((out / "summary.md").string(), md);
  if (!plot) return;
  const std::string log = (out / "plot.log").string();
  // x: the first parameter's (first) pointer; the other pointers of a zipped first parameter vary with it.
  std::vector<std::string> argv{plot_python(), std::string(TISSUE_SOURCE_DIR) + "/scripts/plot_sweep.py",
                                (out / "summary.csv").string(), (out / "sweep.png").string(),
                                "--x", spec.parameters.front().pointers.front(), "--title", spec.name};
  for (std::size_t j = 1; j < spec.parameters.front().pointers.size(); ++j)
    argv.insert(argv.end(), {"--with", spec.parameters.front().pointers[j]});
  const ProcessOutcome p = run_process(argv, log);
  if (p.ok())
    fs::remove(log);
  else
    std::cerr << fmt::format("warning: sweep.png not written ({}); see {}\n", p.error, log);
}

}  // namespace

int run_sweep_command(const std::string& sweep_file, const SweepOptions& options, bool dry_run,
                      const std::string& tissue_binary) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("sweep: " + why);
  const SweepSpec spec = load_sweep(sweep_file);
  const std::vector<SweepRun> runs = expand_sweep(spec);  // every case validated before anything runs
  const fs::path out = options.out_dir.empty() ? fs::path("results/sweeps") / spec.name : fs::path(options.out_dir);
  if (dry_run) {
    std::cout << fmt::format("{}: {} valid runs (results would go to {}):\n", sweep_file, runs.size(), out.string());
    const std::vector<std::string> columns = spec.columns();
    for (const auto& run : runs) {
      std::cout << "  " << run.id;
      for (std::size_t i = 0; i < columns.size(); ++i)
        std::cout << fmt::format("  {} = {}", columns[i], value_text(run.values[i]));
      std::cout << "\n";
    }
    if (!spec.compare.arguments().empty())
      std::cout << fmt::format("each run: tissue compare CASE --out DIR --no-plot {}{}\n",
                               fmt::join(spec.compare.arguments(), " "),
                               spec.compare.reference == "extrapolated"
                                   ? " (every run's mesh size is a level of that study; whether its FEM samples "
                                     "equal the level's is checked by each compare after its FEM solve)"
                                   : "");
    return 0;
  }
  SweepOptions opt = options;
  opt.out_dir = out.string();
  // Several children at once share the cores: each gets its share, none waits for a core another's threads hold.
  const int workers = sweep_workers(spec, opt);
  const SweepReport report =
      run_sweep(spec, runs, opt, compare_in_child_process(tissue_binary, false, spec.compare.arguments(),
                                                          workers > 1 ? threads_per_child(workers) : 0));
  write_sweep_summary(spec, runs, out, options.plot);
  std::cout << fmt::format("{}: {} runs, {} skipped (done before), {} succeeded, {} failed; wrote {}\n", spec.name,
                           report.total, report.skipped, report.succeeded, report.failed,
                           (out / "summary.md").string());
  return report.failed == 0 ? 0 : 1;
}

}  // namespace experiments
