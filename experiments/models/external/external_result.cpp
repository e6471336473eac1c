#include "experiments/models/external/external_result.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

namespace experiments {
namespace {

/// The columns of samples.csv (write_samples_csv): the required ones, then the optional cut columns, which the
/// comparator does not read (its flags come from the case's own cut).
const std::vector<std::string>& required_columns() {
  static const std::vector<std::string> columns{"sample", "x_mm",  "y_mm",  "z_mm",
                                                "ux_mm",  "uy_mm", "uz_mm", "magnitude_mm"};
  return columns;
}
const std::vector<std::string>& optional_columns() {
  static const std::vector<std::string> columns{"cut_distance_mm", "lip"};
  return columns;
}

std::string expected_header() {
  std::string h;
  for (const auto& c : required_columns()) h += (h.empty() ? "" : ",") + c;
  return h + "[,cut_distance_mm[,lip]]";
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return s;
}

/// "x_m" for "x_mm": the same quantity in another unit (the part after the last '_').
bool same_quantity_other_unit(const std::string& found, const std::string& expected) {
  const auto f = found.rfind('_'), e = expected.rfind('_');
  return f != std::string::npos && e != std::string::npos && found.substr(0, f) == expected.substr(0, e) &&
         found.substr(f + 1) != expected.substr(e + 1);
}

void check_header(const std::string& file, const std::vector<std::string>& header) {
  const auto& required = required_columns();
  const auto& optional = optional_columns();
  for (std::size_t i = 0; i < header.size(); ++i) {
    const bool is_required = i < required.size();
    if (!is_required && i >= required.size() + optional.size())
      throw ExternalResultError(file, 1, fmt::format("column {} \"{}\" is not a column of samples.csv; expected the "
                                                     "header {}",
                                                     i + 1, header[i], expected_header()));
    const std::string& expected = is_required ? required[i] : optional[i - required.size()];
    if (header[i] == expected) continue;
    if (same_quantity_other_unit(header[i], expected))
      throw ExternalResultError(
          file, 1,
          fmt::format("column {} is \"{}\", but the file must be in millimetres: expected \"{}\" (write the positions "
                      "and displacements in mm, as samples.csv does)",
                      i + 1, header[i], expected));
    throw ExternalResultError(file, 1, fmt::format("column {} is \"{}\", expected \"{}\": the header must be {} (the "
                                                   "columns of the samples.csv that `tissue solve` writes)",
                                                   i + 1, header[i], expected, expected_header()));
  }
  if (header.size() < required.size())
    throw ExternalResultError(file, 1, fmt::format("{} columns, expected at least {}: the header must be {}",
                                                   header.size(), required.size(), expected_header()));
}

std::string quoted(const std::string& s) { return s.empty() ? std::string("an empty field") : "\"" + s + "\""; }

/// A finite number filling the whole field, or a refusal naming the line and the column.
double parse_number(const std::string& file, int line, const std::string& column, const std::string& field) {
  double v = 0.0;
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, v);
  if (field.empty() || ec != std::errc() || ptr != end)
    throw ExternalResultError(file, line, fmt::format("column {}: expected a number, got {}", column, quoted(field)));
  if (!std::isfinite(v))
    throw ExternalResultError(file, line, fmt::format("column {}: expected a finite number, got {}", column, field));
  return v;
}

long parse_integer(const std::string& file, int line, const std::string& column, const std::string& field,
                   const std::string& what) {
  long v = 0;
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, v);
  if (field.empty() || ec != std::errc() || ptr != end)
    throw ExternalResultError(file, line, fmt::format("column {}: expected {}, got {}", column, what, quoted(field)));
  return v;
}

struct Row {
  int line = 0;
  long sample = 0;
  Eigen::Vector3d x_mm, u_mm;
};

Row parse_row(const std::string& file, int line, const std::vector<std::string>& header,
              const std::vector<std::string>& fields) {
  if (fields.size() != header.size())
    throw ExternalResultError(file, line, fmt::format("{} fields, expected {} (one per column of the header)",
                                                      fields.size(), header.size()));
  Row r;
  r.line = line;
  r.sample = parse_integer(file, line, "sample", fields[0], "a sample index (an integer >= 0)");
  if (r.sample < 0)
    throw ExternalResultError(file, line, fmt::format("column sample: expected a sample index (an integer >= 0), got "
                                                      "{}",
                                                      r.sample));
  for (int k = 0; k < 3; ++k) {
    r.x_mm(k) = parse_number(file, line, header[1 + k], fields[1 + k]);
    r.u_mm(k) = parse_number(file, line, header[4 + k], fields[4 + k]);
  }
  const double magnitude = parse_number(file, line, "magnitude_mm", fields[7]);
  const double norm = r.u_mm.norm();
  if (std::abs(magnitude - norm) > kExternalMagnitudeTolerance * norm + 1e-9)
    throw ExternalResultError(file, line, fmt::format("column magnitude_mm: expected ‖(ux, uy, uz)‖ = {:.9g} mm (eq. "
                                                      "33; within {:g} of it), got {}",
                                                      norm, kExternalMagnitudeTolerance, fields[7]));
  // The cut columns are optional and not read by the comparator; when filled, they must still mean what they say.
  if (fields.size() > 8 && !fields[8].empty() && !(parse_number(file, line, "cut_distance_mm", fields[8]) >= 0.0))
    throw ExternalResultError(file, line, fmt::format("column cut_distance_mm: expected empty or a distance >= 0 mm, "
                                                      "got {}",
                                                      fields[8]));
  if (fields.size() > 9 && !fields[9].empty()) {
    const long lip = parse_integer(file, line, "lip", fields[9], "empty, -1, 0 or 1");
    if (lip < -1 || lip > 1)
      throw ExternalResultError(file, line, fmt::format("column lip: expected empty, -1, 0 or 1, got {}", lip));
  }
  return r;
}

std::string list_of(const std::vector<long>& values) {
  std::string s;
  for (std::size_t i = 0; i < values.size() && i < 10; ++i) s += (i ? ", " : "") + std::to_string(values[i]);
  return values.size() > 10 ? s + fmt::format(" and {} more", values.size() - 10) : s;
}

std::string point_mm(const Eigen::Vector3d& x_mm) { return fmt::format("({:.6f}, {:.6f}, {:.6f}) mm", x_mm(0), x_mm(1), x_mm(2)); }

}  // namespace

ExternalResultError::ExternalResultError(const std::string& file, int line, const std::string& what_expected)
    : std::runtime_error(file + ": " + (line > 0 ? fmt::format("line {}: ", line) : std::string()) + what_expected),
      file_(file),
      line_(line) {}

ExternalSpec parse_external_spec(const std::string& argument) {
  const std::string where = "--external " + argument;
  const auto eq = argument.find('=');
  if (eq == std::string::npos)
    throw ExternalResultError(where, 0, "expected NAME=FILE (the model's name, '=', a CSV file of its samples)");
  ExternalSpec spec{argument.substr(0, eq), argument.substr(eq + 1)};
  if (spec.name.empty()) throw ExternalResultError(where, 0, "expected NAME=FILE with a non-empty NAME");
  const auto bad = std::find_if(spec.name.begin(), spec.name.end(), [](unsigned char ch) {
    return !(std::isalnum(ch) || ch == '_' || ch == '-' || ch == '.');
  });
  if (bad != spec.name.end())
    throw ExternalResultError(where, 0, fmt::format("NAME \"{}\" holds '{}': expected letters, digits, '_', '-' or '.' "
                                                    "only (it becomes a CSV field, a table column and a JSON key)",
                                                    spec.name, *bad));
  if (spec.file.empty()) throw ExternalResultError(where, 0, "expected NAME=FILE with a non-empty FILE");
  return spec;
}

void check_external_names(const std::vector<ExternalSpec>& specs, const std::vector<std::string>& builtin_names) {
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const std::string where = "--external " + specs[i].name + "=" + specs[i].file;
    for (const auto& builtin : builtin_names)
      if (lower(specs[i].name) == lower(builtin))
        throw ExternalResultError(where, 0, fmt::format("NAME \"{}\" is a built-in model's name; expected another "
                                                        "name (the built-in models are {})",
                                                        specs[i].name, fmt::join(builtin_names, ", ")));
    for (std::size_t j = 0; j < i; ++j)
      if (lower(specs[i].name) == lower(specs[j].name))
        throw ExternalResultError(where, 0, fmt::format("NAME \"{}\" is given twice (also as --external {}={}); "
                                                        "expected one name per external result",
                                                        specs[i].name, specs[j].name, specs[j].file));
  }
}

ExternalSamples read_external_samples(const std::string& file, int expected_count) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw ExternalResultError(file, 0, "expected a CSV of sample displacements (the columns of samples.csv), but the "
                                       "file does not exist");
  if (!std::filesystem::is_regular_file(file, ec))
    throw ExternalResultError(file, 0, "expected a CSV file of sample displacements, but this is not a regular file");
  std::ifstream in(file);
  if (!in) throw ExternalResultError(file, 0, "expected a readable CSV file, but it cannot be opened");

  std::vector<std::string> header;
  std::vector<Row> rows;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();         // written on Windows
    if (line == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);  // a UTF-8 byte-order mark (spreadsheets)
    if (line == 1) {
      header = split_fields(text);
      check_header(file, header);
      continue;
    }
    if (trim(text).empty()) continue;
    rows.push_back(parse_row(file, line, header, split_fields(text)));
  }
  if (line == 0)
    throw ExternalResultError(file, 1, fmt::format("expected the header {}, but the file is empty", expected_header()));

  const auto n = static_cast<std::size_t>(expected_count);
  const std::string samples_range = fmt::format("samples 0 to {}", expected_count - 1);
  if (rows.size() > n)
    throw ExternalResultError(file, rows[n].line,
                              fmt::format("a row beyond the case's {} samples: the file holds {} sample rows, expected "
                                          "{}, one per sample of the case ({})",
                                          expected_count, rows.size(), expected_count, samples_range));
  std::map<long, int> line_of_sample;
  for (const Row& r : rows) {
    if (r.sample >= expected_count)
      throw ExternalResultError(file, r.line,
                                fmt::format("sample {} is not a sample of the case, which has {} ({}; indices are "
                                            "0-based, as in samples.csv)",
                                            r.sample, expected_count, samples_range));
    const auto [it, inserted] = line_of_sample.emplace(r.sample, r.line);
    if (!inserted)
      throw ExternalResultError(file, r.line, fmt::format("sample {} again (first on line {}); expected each sample "
                                                          "index once",
                                                          r.sample, it->second));
  }
  if (rows.size() < n) {
    std::vector<long> missing;
    for (long i = 0; i < expected_count; ++i)
      if (!line_of_sample.count(i)) missing.push_back(i);
    throw ExternalResultError(
        file, 0,
        rows.empty()
            ? fmt::format("no sample rows after the header on line 1; expected {}, one per sample of the case ({})",
                          expected_count, samples_range)
            : fmt::format("{} sample rows (lines {} to {}), expected {}, one per sample of the case ({}): missing "
                          "sample{} {}",
                          rows.size(), rows.front().line, rows.back().line, expected_count, samples_range,
                          missing.size() == 1 ? "" : "s", list_of(missing)));
  }

  ExternalSamples samples;
  samples.file = file;
  samples.points.resize(expected_count, 3);
  samples.displacements.resize(expected_count, 3);
  samples.lines.resize(n);
  for (const Row& r : rows) {
    samples.points.row(r.sample) = r.x_mm.transpose() * 1e-3;
    samples.displacements.row(r.sample) = r.u_mm.transpose() * 1e-3;
    samples.lines[static_cast<std::size_t>(r.sample)] = r.line;
  }
  return samples;
}

ModelResult external_model_result(const ExternalSamples& samples, const std::string& name,
                                  const Eigen::MatrixXd& case_points) {
  if (samples.points.rows() != case_points.rows())
    throw ExternalResultError(samples.file, 0, fmt::format("{} samples, expected the case's {}", samples.points.rows(),
                                                           case_points.rows()));
  double largest_offset = 0.0;
  for (Eigen::Index i = 0; i < case_points.rows(); ++i) {
    const Eigen::Vector3d x = samples.points.row(i).transpose(), expected = case_points.row(i).transpose();
    const double offset = (x - expected).norm();
    largest_offset = std::max(largest_offset, offset);
    if (offset <= kExternalPositionTolerance) continue;
    std::string hint = "the rows must be this case's samples, by index (`tissue case check CONFIG` lists them, and "
                       "every `tissue solve` writes them to its samples.csv)";
    if ((x * 1e3 - expected).norm() <= kExternalPositionTolerance) {
      hint = "the file's positions look like metres, but samples.csv is in mm";
    } else {
      for (Eigen::Index j = 0; j < case_points.rows(); ++j)
        if (j != i && (x - case_points.row(j).transpose()).norm() <= kExternalPositionTolerance)
          hint = fmt::format("that is the position of the case's sample {}: each row's sample index must be that of "
                             "the case's sample at its position",
                             j);
    }
    throw ExternalResultError(
        samples.file, samples.lines[static_cast<std::size_t>(i)],
        fmt::format("sample {} is at {}, but the case's sample {} is at {}, {:.6f} mm away; expected within {:g} mm; {}",
                    i, point_mm(x * 1e3), i, point_mm(expected * 1e3), offset * 1e3,
                    kExternalPositionTolerance * 1e3, hint));
  }
  ModelResult r;
  r.model = name;
  r.role = "external";
  r.sample_points = case_points;
  r.sample_displacements = samples.displacements;
  r.details = {{"source", samples.file},
               {"position_tolerance_mm", kExternalPositionTolerance * 1e3},
               {"largest_position_offset_mm", largest_offset * 1e3}};
  return r;
}

}  // namespace experiments
