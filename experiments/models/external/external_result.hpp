#pragma once
// Sample displacements computed by another program, scored by `tissue compare --external NAME=FILE.csv` beside the
// built-in models. The file has the columns of the samples.csv every solve writes (write_samples_csv); it is read and
// checked here, then matched BY POSITION to the case's samples and turned into a ModelResult of role "external", so
// that the comparator applies to it the same eq. 34 RMSE, flags and error bar as to its own models.
//
// Every refusal is an ExternalResultError naming the file, the line and what was expected. compare runs these checks
// before any solve: reading and the count right after the case is loaded, the positions right after the geometry
// (seconds), so a wrong file never costs the minutes of a solve.
//
// Units: the CSV is in mm; ExternalSamples and ModelResult hold metres. Plain functions and values; no shared state.
#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/models/model_result.hpp"

namespace experiments {

/// [m] How far a row's position may lie from the case's sample of the same index: 1 µm.
/// - Far above the rounding of any honest file: samples.csv writes positions in mm with 6 decimals (5e-7 mm), and a
///   program printing 7 significant digits (CalculiX's default) rounds coordinates below 1 m by at most 5e-5 mm.
/// - Far below the spacing of the samples (millimetres), so a row of another sample (a shifted or reordered index) and
///   a position in metres are both caught.
/// - Harmless to the score: a point 1 µm off moves the displacement by about strain × 1 µm, at most 1e-4 mm at the 10 %
///   strain of a probe, a hundredth of the smallest RMSE we report (0.01 mm).
inline constexpr double kExternalPositionTolerance = 1e-6;

/// [-] How far magnitude_mm may differ from ‖(ux, uy, uz)‖ relative to it (plus 1e-9 mm): a file whose magnitude is
/// not that of its own components is inconsistent (another step, another unit). 1e-3 admits components printed with
/// four significant digits.
inline constexpr double kExternalMagnitudeTolerance = 1e-3;

/// A refused external result. what() is "FILE: line N: <what was expected and what was found>", or "FILE: ..." when
/// the problem is not on one line (a missing file, a missing sample).
class ExternalResultError : public std::runtime_error {
 public:
  ExternalResultError(const std::string& file, int line, const std::string& what_expected);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  ///< 1-based; 0 when the problem is not on one line

 private:
  std::string file_;
  int line_;
};

/// One `--external NAME=FILE` argument.
struct ExternalSpec {
  std::string name;  ///< the model's name in summary.json, table.md and samples.csv
  std::string file;
};

/// Splits "NAME=FILE" at the first '='. Throws ExternalResultError (file "--external ARGUMENT") when there is no
/// '=', the FILE is empty, or the NAME is empty or not made of letters, digits, '_', '-' and '.' (it becomes a CSV
/// field, a Markdown column, a JSON key and a VTU array name).
ExternalSpec parse_external_spec(const std::string& argument);

/// Refuses (ExternalResultError) a NAME that is a built-in model's (`builtin_names`, e.g. fem, enrichment,
/// visibility) or given twice; both compared ignoring case, so that the tables stay unambiguous.
void check_external_names(const std::vector<ExternalSpec>& specs, const std::vector<std::string>& builtin_names);

/// The rows of an external CSV, in the case's sample order (row i is sample i).
struct ExternalSamples {
  std::string file;
  Eigen::MatrixXd points;         ///< #samples by 3, the file's positions [m]
  Eigen::MatrixXd displacements;  ///< #samples by 3 [m]
  std::vector<int> lines;         ///< the file's line of each sample (1-based), for the position check's messages
};

/// Reads `file` and checks everything that needs only the case's sample count: the header (the columns of
/// samples.csv, in mm, the cut columns optional), finite numbers in every field, magnitude_mm consistent with the
/// components, each sample index in 0 .. expected_count - 1 exactly once, and `expected_count` rows.
ExternalSamples read_external_samples(const std::string& file, int expected_count);

/// Checks each row's position against the case's sample of the same index (within kExternalPositionTolerance) and
/// returns the result as a ModelResult: model `name`, role "external", the case's sample points, the file's
/// displacements, no timings, details {source, position_tolerance_mm, largest_position_offset_mm}.
/// @param case_sample_points  #samples by 3 [m] (core::Geometry::sample_points)
ModelResult external_model_result(const ExternalSamples& samples, const std::string& name,
                                  const Eigen::MatrixXd& case_sample_points);

}  // namespace experiments
