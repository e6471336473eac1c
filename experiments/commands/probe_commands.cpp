#include "experiments/commands/probe_commands.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "core/case.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/studies/realtime_loop.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace experiments {
namespace {

struct ProbeArguments {
  std::string surrogate, config, trace, out;
  double rate = 1000.0;
  double contact_tolerance_mm = 0.0;
  bool realtime = true;
  double spin_us = 100.0;
  int cpu = -1;
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
  if (!r.on_trained_contact && s.data().region)
    out += fmt::format(
        " [point outside the trained contact region ({:.2f} mm around its centre): the nearest trained contact "
        "node's response is used, {:.2f} mm away]",
        s.data().region->radius * 1e3, r.contact_distance * 1e3);
  else if (!r.on_trained_contact)
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
  if (!a.realtime && a.cpu >= 0)
    throw std::runtime_error(
        "--cpu pins the real-time loop, which --no-realtime turns off: drop one of them");
  if (a.spin_us >= 1e6 / a.rate)
    throw std::runtime_error(fmt::format(
        "--spin-us {:g} is not shorter than the period ({:g} us at {:g} Hz): lower it, or the rate",
        a.spin_us, 1e6 / a.rate, a.rate));
  const meshless::Surrogate s = load(a);
  const std::vector<Sample> samples = read_trace(a.trace);
  const std::string out =
      a.out.empty() ? std::filesystem::path(a.trace).stem().string() + ".probe.csv" : a.out;
  std::cerr << fmt::format("probe: replaying {} samples of {} at {:g} Hz (deadline {:.0f} us each)\n",
                           samples.size(), a.trace, a.rate, 1e6 / a.rate);

  std::vector<meshless::SurrogateResponse> responses(samples.size());
  core::PointMatrix u(s.num_surface_nodes(), 3);  // allocated once, outside the loop
  FixedRateLoopOptions options;
  options.rate_hz = a.rate;
  options.spin_ns = static_cast<MonotonicNs>(std::llround(a.spin_us * 1e3));
  options.scheduling.realtime = a.realtime;
  options.scheduling.cpu = a.cpu;
  LoopScheduling scheduling;
  const std::vector<LoopSample> timing = run_fixed_rate_loop(
      samples.size(), options,
      [&](std::size_t i) { responses[i] = s.query(samples[i].x * 1e-3, samples[i].f, &u); },
      // Before the first release, on the loop's thread: say what was refused (once, now rather than after the
      // replay), then an untimed query puts its code and the surrogate's data in the loop core's caches.
      [&] {
        for (const std::string& refusal : scheduling.refusals) std::cerr << "probe: " << refusal << "\n";
        s.query(samples.front().x * 1e-3, samples.front().f, &u);
      },
      &scheduling);
  const LoopSummary summary = summarize(timing);
  const DeadlineSchedule schedule(0, a.rate, options.spin_ns);  // the offsets from the start, for the CSV

  int clamped = 0, off_contact = 0;
  std::string csv =
      "sample,t_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,release_us,latency_us,compute_us,missed_deadline,contact_"
      "node,"
      "contact_distance_mm,on_trained_contact,in_contact_region,force_in_range,ux_mm,uy_mm,uz_mm,max_surface_mm,max_surface_"
      "node,woke_late_us\n";
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const meshless::SurrogateResponse& r = responses[i];
    const LoopSample& t = timing[i];
    clamped += !r.force_in_range;
    off_contact += !r.on_trained_contact;
    const Sample& p = samples[i];
    csv += fmt::format(
        "{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.3f},{:.3f},{:.3f},{},{},{:.4f},{},{},{},"
        "{:.6g},{:.6g},{:.6g},{:.6g},{},{:.3f}\n",
        i, p.t, p.x.x(), p.x.y(), p.x.z(), p.f.x(), p.f.y(), p.f.z(),
        1e-3 * static_cast<double>(schedule.release(static_cast<std::int64_t>(i))), 1e-3 * t.latency_ns,
        1e-3 * t.compute_ns, t.missed ? 1 : 0, s.data().surface_vertex[r.contact_node],
        r.contact_distance * 1e3, r.on_trained_contact ? 1 : 0, r.in_contact_region ? 1 : 0,
        r.force_in_range ? 1 : 0,
        r.contact_displacement.x() * 1e3, r.contact_displacement.y() * 1e3, r.contact_displacement.z() * 1e3,
        r.max_surface_displacement * 1e3, s.data().surface_vertex[r.max_surface_node], 1e-3 * t.woke_late_ns);
  }
  write_text_atomically(out, csv);
  const LoopSummary& m = summary;
  std::cout << fmt::format(
      "replayed {} samples at {:g} Hz on '{}' ({} surface nodes): latency p50 {:.1f} us, p99 {:.1f} us, max "
      "{:.1f} us (query alone p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us); missed deadlines: {} of {} "
      "({:.2f} %; missed = answered after its period's end, the next release)\n",
      samples.size(), a.rate, s.data().case_name, s.num_surface_nodes(), m.latency_p50_us, m.latency_p99_us,
      m.latency_max_us, m.compute_p50_us, m.compute_p99_us, m.compute_max_us, m.missed, m.samples,
      m.missed_percent);
  std::cout << fmt::format(
      "scheduling: {}; each sleep (clock_nanosleep to an absolute time) ends {:g} us before the release, "
      "then spins: it ended late by p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us\n",
      a.realtime ? scheduling.describe()
                 : "normal scheduler (--no-realtime): SCHED_OTHER, not pinned, memory not locked",
      a.spin_us, m.woke_late_p50_us, m.woke_late_p99_us, m.woke_late_max_us);
  for (const std::string& refusal : scheduling.refusals) std::cout << "refused: " << refusal << "\n";
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
  auto* probe = app.add_subcommand("probe", "Query a surrogate file as a haptic probe (stdin, or a replayed trace)");
  probe->footer("Reads 'x y z fx fy fz' lines (mm, N) from stdin and prints the contact node's displacement and the largest\n"
                "surface displacement, or replays a device trace at a fixed rate with deadlines (--trace;\n"
                "docs/SURROGATE.md).");
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
      "--realtime,!--no-realtime", args.realtime,
      "The replay loop's thread as a haptic thread runs (the default): pinned to one CPU (--cpu, else the "
      "last one allowed), SCHED_FIFO priority 50, memory locked (mlockall); each refusal is reported and the "
      "loop goes on without it. --no-realtime: the normal scheduler, no pin, no lock, to compare with");
  probe
      ->add_option("--spin-us", args.spin_us,
                   "The replay's sleep ends this long [us] before each release and spins to it, absorbing "
                   "the kernel's wake-up delay (docs/SURROGATE.md §7)")
      ->check(CLI::Range(0.0, 1e5))
      ->capture_default_str();
  probe
      ->add_option("--cpu", args.cpu,
                   "Pin the replay loop to this CPU (default: the last one the process may use); refused "
                   "unless the process's affinity allows it")
      ->check(CLI::NonNegativeNumber);
  probe->callback([] { throw CommandResult{args.trace.empty() ? run_interactive(args) : run_replay(args)}; });
}

}  // namespace experiments
