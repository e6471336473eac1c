#include "experiments/export/calculix_results.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace experiments {

CalculixDisplacements read_calculix_dat_displacements(const std::filesystem::path& dat_file) {
  std::ifstream in(dat_file);
  if (!in)
    throw std::runtime_error(fmt::format("cannot read {}; expected the .dat file ccx writes (run `ccx -i JOB` in the "
                                         "export folder first)",
                                         dat_file.string()));
  const std::string header = "displacements (vx,vy,vz) for set";
  CalculixDisplacements result;
  bool any_table = false, in_table = false;
  int table_rows = 0;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::size_t at = line.find(header);
    if (at != std::string::npos) {
      const std::size_t time_at = line.find("and time");
      if (time_at == std::string::npos)
        throw std::runtime_error(fmt::format("{}:{}: a displacement table without its time", dat_file.string(),
                                             line_number));
      const double time = std::stod(line.substr(time_at + 8));
      if (!any_table || time > result.time) result.by_node.clear();  // a later time supersedes the earlier tables
      if (!any_table || time >= result.time) result.time = time;
      any_table = true;
      in_table = time >= result.time;
      table_rows = 0;
      continue;
    }
    if (!in_table) continue;
    if (line.find_first_not_of(" \t\r") == std::string::npos) {
      if (table_rows > 0) in_table = false;  // the blank line after the header, or the table's end
      continue;
    }
    std::istringstream row(line);
    long long node = 0;
    Eigen::Vector3d u;
    if (!(row >> node >> u.x() >> u.y() >> u.z()) || node <= 0) {
      in_table = false;  // another kind of table follows (stresses, forces): not ours
      continue;
    }
    result.by_node[static_cast<std::size_t>(node)] = u;
    ++table_rows;
  }
  if (!any_table || result.by_node.empty())
    throw std::runtime_error(fmt::format("{} holds no nodal displacement table; expected the output of *NODE PRINT "
                                         "with U (the deck `tissue export` writes asks for it)",
                                         dat_file.string()));
  return result;
}

}  // namespace experiments
