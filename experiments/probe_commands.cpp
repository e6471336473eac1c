#include "experiments/probe_commands.hpp"

#include <fmt/format.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "core/case.hpp"
#include "experiments/progress.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace experiments {
namespace {

using Clock = std::chrono::steady_clock;

struct ProbeArguments {
  std::string surrogate, config, trace, out;
  double rate = 1000.0;
  double contact_tolerance_mm = 0.0;
  bool realtime = false;
};

/// SCHED_FIFO for the replay loop while it lives (a haptic thread's usual scheduling), the previous policy
/// after.
class RealtimeScheduling {
 public:
  explicit RealtimeScheduling(bool wanted) {
    if (!wanted) return;
    previous_policy_ = sched_getscheduler(0);
    sched_getparam(0, &previous_);
    sched_param p{};
    p.sched_priority = 50;
    granted_ = sched_setscheduler(0, SCHED_FIFO, &p) == 0;
    if (!granted_) error_ = std::strerror(errno);
  }
  ~RealtimeScheduling() {
    if (granted_) sched_setscheduler(0, previous_policy_, &previous_);
  }
  std::string describe(bool wanted) const {
    if (!wanted) return "default scheduling (--realtime not given)";
    return granted_ ? "SCHED_FIFO priority 50" : "default scheduling (SCHED_FIFO refused: " + error_ + ")";
  }

 private:
  bool granted_ = false;
  int previous_policy_ = SCHED_OTHER;
  sched_param previous_{};
  std::string error_;
};

/// One device sample: contact point [mm] and force [N].
struct Sample {
  double t = 0.0;  ///< [s] as given in the trace (informative: the replay runs at the fixed rate)
  Eigen::Vector3d x = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
};

/// Parse `count` numbers separated by blanks or commas; nullopt when the line holds anything else.
std::optional<std::vector<double>> parse_numbers(std::string line, int count) {
  std::replace(line.begin(), line.end(), ',', ' ');
  std::istringstream in(line);
  std::vector<double> v;
  std::string token;
  while (in >> token) {
    char* end = nullptr;
    const double x = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || !std::isfinite(x)) return std::nullopt;
    v.push_back(x);
  }
  if (static_cast<int>(v.size()) != count) return std::nullopt;
  return v;
}

meshless::Surrogate load(const ProbeArguments& a) {
  std::optional<std::string> hash;
  if (!a.config.empty()) hash = meshless::surrogate_case_hash(core::load_case(a.config));
  return meshless::Surrogate(meshless::read_surrogate(a.surrogate, hash), a.contact_tolerance_mm * 1e-3);
}

std::string flags(const meshless::Surrogate& s, const meshless::SurrogateResponse& r) {
  std::string out;
  if (!r.force_in_range)
    out += fmt::format(
        " [force outside the trained range +-{:g} N per component: clamped to ({:.4g}, {:.4g}, {:.4g}) N]",
        s.data().max_force, r.force.x(), r.force.y(), r.force.z());
  if (!r.on_trained_contact)
    out += fmt::format(
        " [point {:.2f} mm from the nearest trained contact node, beyond {:.2f} mm: its response is used]",
        r.contact_distance * 1e3, s.contact_tolerance() * 1e3);
  return out;
}

int run_interactive(const ProbeArguments& a) {
  const meshless::Surrogate s = load(a);
  std::cerr << fmt::format(
      "probe: surrogate of '{}' ({} contact node(s), {} surface nodes, forces within +-{:g} N per "
      "component); enter "
      "one 'x y z fx fy fz' (mm, N) per line, end with Ctrl-D\n",
      s.data().case_name, s.num_contacts(), s.num_surface_nodes(), s.data().max_force);
  core::PointMatrix u;
  std::string line;
  int number = 0, errors = 0;
  while (std::getline(std::cin, line)) {
    ++number;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto v = parse_numbers(line, 6);
    if (!v) {
      ++errors;
      std::cout << fmt::format("error: line {}: expected six numbers 'x y z fx fy fz' (mm, N), got '{}'\n",
                               number, line);
      std::cout.flush();
      continue;
    }
    const Eigen::Vector3d x = Eigen::Vector3d((*v)[0], (*v)[1], (*v)[2]) * 1e-3, f((*v)[3], (*v)[4], (*v)[5]);
    const meshless::SurrogateResponse r = s.query(x, f, &u);
    const Eigen::Vector3d uc = r.contact_displacement * 1e3;
    const Eigen::Vector3d xm = s.data().surface_position.row(r.max_surface_node).transpose() * 1e3;
    std::cout << fmt::format(
        "contact node {} ({:.2f} mm away): u = ({:.5f}, {:.5f}, {:.5f}) mm, |u| = {:.5f} mm; largest surface "
        "|u| = "
        "{:.5f} mm at ({:.1f}, {:.1f}, {:.1f}) mm{}\n",
        s.data().surface_vertex[r.contact_node], r.contact_distance * 1e3, uc.x(), uc.y(), uc.z(), uc.norm(),
        r.max_surface_displacement * 1e3, xm.x(), xm.y(), xm.z(), flags(s, r));
    std::cout.flush();
  }
  if (errors) std::cerr << fmt::format("probe: {} malformed line(s) skipped\n", errors);
  return 0;
}

std::vector<Sample> read_trace(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the trace (does it exist?)");
  std::vector<Sample> samples;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    if (samples.empty() && std::isalpha(static_cast<unsigned char>(line[first]))) continue;  // the header
    const auto v = parse_numbers(line, 7);
    if (!v)
      throw std::runtime_error(fmt::format(
          "{}:{}: expected seven numbers 't,x,y,z,fx,fy,fz' (s, mm, N), got '{}'", path, number, line));
    Sample s;
    s.t = (*v)[0];
    s.x = Eigen::Vector3d((*v)[1], (*v)[2], (*v)[3]);
    s.f = Eigen::Vector3d((*v)[4], (*v)[5], (*v)[6]);
    samples.push_back(s);
  }
  if (samples.empty()) throw std::runtime_error(path + ": the trace holds no sample");
  return samples;
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(p / 100.0 * v.size()));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];  // nearest rank
}

/// Atomic write of a text file: a temporary name in the same folder, then rename.
void write_text_atomically(const std::string& path, const std::string& text) {
  const std::filesystem::path destination(path);
  const std::filesystem::path folder = destination.has_parent_path() ? destination.parent_path() : ".";
  std::string temporary = (folder / ("." + destination.filename().string() + ".XXXXXX")).string();
  const int fd = mkstemp(temporary.data());
  if (fd < 0)
    throw std::runtime_error(
        fmt::format("{}: cannot create a file in {}: {}", path, folder.string(), std::strerror(errno)));
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  const int saved = errno;
  if (::close(fd) != 0 || written != text.size()) {
    std::remove(temporary.c_str());
    throw std::runtime_error(fmt::format("{}: writing failed: {}", path, std::strerror(saved)));
  }
  std::error_code ec;
  std::filesystem::rename(temporary, destination, ec);
  if (ec) {
    std::remove(temporary.c_str());
    throw std::runtime_error(fmt::format("{}: cannot move the file into place: {}", path, ec.message()));
  }
}

int run_replay(const ProbeArguments& a) {
  const meshless::Surrogate s = load(a);
  const std::vector<Sample> samples = read_trace(a.trace);
  const std::string out =
      a.out.empty() ? std::filesystem::path(a.trace).stem().string() + ".probe.csv" : a.out;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / a.rate));
  std::cerr << fmt::format("probe: replaying {} samples of {} at {:g} Hz (deadline {:.0f} us each)\n",
                           samples.size(), a.trace, a.rate, 1e6 / a.rate);

  struct Record {
    meshless::SurrogateResponse r;
    double release_us = 0.0, latency_us = 0.0, compute_us = 0.0;
    bool missed = false;
  };
  std::vector<Record> records(samples.size());
  core::PointMatrix u(s.num_surface_nodes(), 3);  // allocated once, outside the loop
  std::string scheduling;
  {
    const RealtimeScheduling realtime(a.realtime);
    scheduling = realtime.describe(a.realtime);
    const Clock::time_point start = Clock::now() + std::chrono::milliseconds(20);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Clock::time_point release = start + static_cast<Clock::rep>(i) * period;
      // Sleep to just before the release, then spin: the OS wakes sleepers tens of microseconds late.
      std::this_thread::sleep_until(release - std::chrono::microseconds(200));
      while (Clock::now() < release) {
      }
      const Clock::time_point begin = Clock::now();
      Record& rec = records[i];
      rec.r = s.query(samples[i].x * 1e-3, samples[i].f, &u);
      const Clock::time_point done = Clock::now();
      rec.release_us = std::chrono::duration<double, std::micro>(release - start).count();
      rec.latency_us = std::chrono::duration<double, std::micro>(done - release).count();
      rec.compute_us = std::chrono::duration<double, std::micro>(done - begin).count();
      rec.missed = done > release + period;  // the deadline is the next sample's release
    }
  }

  std::vector<double> latency, compute;
  int missed = 0, clamped = 0, off_contact = 0;
  std::string csv =
      "sample,t_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,release_us,latency_us,compute_us,missed_deadline,contact_"
      "node,"
      "contact_distance_mm,on_trained_contact,force_in_range,ux_mm,uy_mm,uz_mm,max_surface_mm,max_surface_"
      "node\n";
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Record& r = records[i];
    latency.push_back(r.latency_us);
    compute.push_back(r.compute_us);
    missed += r.missed;
    clamped += !r.r.force_in_range;
    off_contact += !r.r.on_trained_contact;
    const Sample& p = samples[i];
    csv += fmt::format(
        "{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.3f},{:.3f},{:.3f},{},{},{:.4f},{},{},"
        "{:.6g},{:.6g},{:.6g},{:.6g},{}\n",
        i, p.t, p.x.x(), p.x.y(), p.x.z(), p.f.x(), p.f.y(), p.f.z(), r.release_us, r.latency_us,
        r.compute_us, r.missed ? 1 : 0, s.data().surface_vertex[r.r.contact_node], r.r.contact_distance * 1e3,
        r.r.on_trained_contact ? 1 : 0, r.r.force_in_range ? 1 : 0, r.r.contact_displacement.x() * 1e3,
        r.r.contact_displacement.y() * 1e3, r.r.contact_displacement.z() * 1e3,
        r.r.max_surface_displacement * 1e3, s.data().surface_vertex[r.r.max_surface_node]);
  }
  write_text_atomically(out, csv);
  std::cout << fmt::format(
      "replayed {} samples at {:g} Hz on '{}' ({} surface nodes, {}): latency p50 {:.1f} us, p99 {:.1f} us, "
      "max "
      "{:.1f} us (query alone p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us); missed deadlines: {} of {}\n",
      samples.size(), a.rate, s.data().case_name, s.num_surface_nodes(), scheduling, percentile(latency, 50),
      percentile(latency, 99), *std::max_element(latency.begin(), latency.end()), percentile(compute, 50),
      percentile(compute, 99), *std::max_element(compute.begin(), compute.end()), missed, samples.size());
  if (clamped || off_contact)
    std::cout << fmt::format(
        "flagged: {} sample(s) with a force outside +-{:g} N (clamped), {} away from every trained "
        "contact node (nearest used)\n",
        clamped, s.data().max_force, off_contact);
  std::cout << fmt::format("wrote {}\n", out);
  return 0;
}

}  // namespace

void add_probe_commands(CLI::App& app) {
  auto* probe = app.add_subcommand("probe",
                                   "Haptic probe mode on a surrogate file (docs/SURROGATE.md): read 'x y z "
                                   "fx fy fz' (mm, N) lines from stdin and "
                                   "print the contact-node displacement and the largest surface "
                                   "displacement, or replay a device trace at a "
                                   "fixed rate with deadlines (--trace)");
  static ProbeArguments args;
  probe->add_option("SURROGATE", args.surrogate, "Surrogate file written by `tissue fit`")->required();
  probe->add_option("--case", args.config,
                    "Refuse the surrogate unless it was fitted on this case file (hash check)");
  probe->add_option(
      "--trace", args.trace,
      "Replay this CSV trace (header then rows t,x,y,z,fx,fy,fz in s, mm, N) instead of reading stdin");
  probe
      ->add_option("--rate", args.rate, "Replay rate [Hz] (each sample's deadline is the next one's release)")
      ->check(CLI::Range(1.0, 1e6));
  probe->add_option("--out", args.out, "Per-sample CSV of the replay (default: TRACE_STEM.probe.csv here)");
  probe
      ->add_option("--contact-tolerance", args.contact_tolerance_mm,
                   "Flag contact points farther than this [mm] from every trained contact node (default: the "
                   "training patch radius)")
      ->check(CLI::NonNegativeNumber);
  probe->add_flag(
      "--realtime", args.realtime,
      "Run the replay loop under SCHED_FIFO (priority 50), as a haptic thread would; reported when refused");
  probe->callback([] { throw CommandResult{args.trace.empty() ? run_interactive(args) : run_replay(args)}; });
}

}  // namespace experiments
