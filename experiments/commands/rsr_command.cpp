#include "experiments/commands/rsr_command.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <iostream>

#include "core/output_directory.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/studies/rsr.hpp"

namespace experiments {
namespace {

struct RsrOptions {
  std::string scores = std::string(TISSUE_SOURCE_DIR) + "/configs/paper_table2_scores.csv";
  std::vector<std::string> lower_is_better;
  std::string out;
};

int run_rsr(const RsrOptions& opt) {
  ScoreTable table;
  RsrResult result;
  try {
    table = read_score_table(opt.scores);
    for (const auto& name : opt.lower_is_better) {
      const auto it = std::find(table.indicators.begin(), table.indicators.end(), name);
      if (it == table.indicators.end())
        throw std::invalid_argument(fmt::format("--lower-is-better {}: {} has no such indicator column", name,
                                                opt.scores));
      table.lower_is_better[static_cast<std::size_t>(it - table.indicators.begin())] = true;
    }
    result = evaluate_rsr(table);
  } catch (const std::invalid_argument& e) {  // bad input: exit 2, like a bad case
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  const std::string md = fmt::format("# Rank-sum-ratio evaluation (`tissue rsr`, paper §5.6)\n\nScores: {}\n\n",
                                     opt.scores) +
                         rsr_markdown(result);
  if (!opt.out.empty()) {
    core::OutputDirectory out(opt.out);
    write_text_file(out.file("rsr.md").string(), md);
    nlohmann::json j = rsr_json(result);
    j["scores_file"] = opt.scores;
    write_text_file(out.file("rsr.json").string(), j.dump(2) + "\n");
    out.commit();
  }
  std::cout << md;
  if (!opt.out.empty()) std::cout << fmt::format("\nwrote rsr.md and rsr.json to {}\n", opt.out);
  return 0;
}

}  // namespace

void add_rsr_command(CLI::App& app) {
  static RsrOptions opt;
  auto* rsr = app.add_subcommand("rsr", "Rank-sum-ratio evaluation of the paper's §5.6 (Tables 3-6)");
  rsr->footer("Ranks (Table 3), RSR (Table 4, eq. 36), probits (Table 5), the regression RSR = a + b·Probit (eq. 37)\n"
              "and the grading (Table 6).");
  rsr->add_option("SCORES", opt.scores,
                  "Score CSV: header `name,I1,...,Im`, one row per object (default: the paper's Table 2)")
      ->capture_default_str();
  rsr->add_option("--lower-is-better", opt.lower_is_better,
                  "Indicator columns where a lower score is better (ranked in reverse)");
  rsr->add_option("--out", opt.out, "Also write rsr.md and rsr.json to this folder (written atomically)");
  rsr->callback([] { throw CommandResult{run_rsr(opt)}; });
}

}  // namespace experiments
