// truecut run CONFIG.hal: load a HAL configuration and run its threads.
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "quiet_option.hpp"
#include "run_machine.hpp"
#include "run_support.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

namespace truecut::cli {
namespace {

const char* kRunHelp =
    "usage: truecut run CONFIG.hal [options]\n"
    "       truecut run MACHINE.json PROGRAM.ngc --out DIR [options]  (see --help there)\n"
    "\n"
    "Loads a .hal wiring file (loadrt, net, setp, addf, ...) and runs its threads.\n"
    "Without --time or --cycles it runs until a component stops it or Ctrl-C (a\n"
    "recorder's trace has no size limit meanwhile). Ctrl-C before --time or --cycles\n"
    "is reached exits 130; the outputs hold the run up to there.\n"
    "\n"
    "options:\n"
    "  --ini FILE             INI file for [SECTION]KEY substitution in the .hal file\n"
    "  --time SECONDS         run this much (simulated) time\n"
    "  --cycles N             run N cycles of the fastest thread\n"
    "  --out DIR              folder for component outputs (created; default .)\n"
    "  --component-path DIR   also search DIR for component NAME.so (repeatable)\n"
    "  --realtime             wall-clock mode: absolute deadlines, latency statistics\n"
    "  --cpu N                (wall clock) pin the servo thread to CPU N\n"
    "  --fifo PRIORITY        (wall clock) SCHED_FIFO priority 1..99 when permitted\n"
    "  --no-mlock             (wall clock) do not lock memory\n"
    "  --spin-us N            (wall clock) busy-wait the last N us before each deadline\n"
    "  --show                 print threads, pins and signals after loading\n"
    "  --dry-run              load and check the configuration, run nothing\n"
    "  --quiet                nothing on stderr but warnings and errors\n"
    "                         (progress is shown on a terminal only)\n"
    "  --help                 this text\n"
    "\n"
    "Components are looked for built in, then as NAME.so in --component-path,\n"
    "$TRUECUT_COMPONENT_PATH (':'-separated) and the folders beside the truecut binary.\n";

std::string us(int64_t ns) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", double(ns) * 1e-3);
  return buf;
}

void print_show(const rt::hal::Hal& h) {
  std::printf("Threads:\n");
  for (const auto& t : h.threads()) {
    std::printf("  %-20s period %lld ns%s\n", t.name.c_str(), (long long)t.period_ns,
                t.uses_fp ? "" : " (nofp)");
    int i = 1;
    for (const auto& f : t.functions)
      std::printf("    %2d %s\n", i++, f.c_str());
  }
  std::printf("Pins:\n");
  for (const auto& p : h.pins())
    std::printf("  %-6s %-4s %-36s %s%s\n", rt::hal::to_string(p.type), rt::hal::to_string(p.dir),
                p.name.c_str(), p.signal.empty() ? "" : "<-> ", p.signal.c_str());
  std::printf("Signals:\n");
  for (const auto& s : h.signals())
    std::printf("  %-6s %-36s %s\n", rt::hal::to_string(s.type), s.name.c_str(),
                h.get_signal(s.name).to_text().c_str());
}

bool ends_with_json(const std::string& arg) {
  return arg.size() > 5 && arg.compare(arg.size() - 5, 5, ".json") == 0;
}

// The arguments that are not options or option values. Options that take a
// value in either form take the next argument unless written --name=value.
std::vector<std::string> positional_arguments(const std::vector<std::string>& argv) {
  static const char* const kFlags[] = {"--realtime", "--no-mlock", "--show",
                                       "--dry-run",  "--quiet",    "--help"};
  std::vector<std::string> positionals;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      positionals.push_back(arg);
      continue;
    }
    const bool flag = std::find(std::begin(kFlags), std::end(kFlags), arg) != std::end(kFlags);
    if (!flag && arg.find('=') == std::string::npos) ++i;  // its value
  }
  return positionals;
}

// The machine form: MACHINE.json PROGRAM.ngc, i.e. a first argument ending in
// .json (a folder or device of that name included: its reader says what it
// is) or two of them, where CONFIG.hal takes one.
bool machine_form(const std::vector<std::string>& argv) {
  const std::vector<std::string> positionals = positional_arguments(argv);
  return (!positionals.empty() && ends_with_json(positionals[0])) || positionals.size() == 2;
}

uint64_t fastest_thread_cycles(const rt::hal::RunReport& r) {
  uint64_t cycles = 0;
  for (const auto& t : r.threads)
    cycles = std::max(cycles, t.cycles);
  return cycles;
}

// Whether the run went as far as --time or --cycles asked (neither given:
// false).
bool limit_reached(const rt::hal::RunLimits& limits, const rt::hal::RunReport& r) {
  if (limits.duration_ns > 0) return r.simulated_ns >= limits.duration_ns;
  if (limits.max_cycles > 0) return fastest_thread_cycles(r) >= limits.max_cycles;
  return false;
}

void report_interrupted_run(const rt::hal::RunLimits& limits, const rt::hal::RunReport& r) {
  if (limits.duration_ns > 0)
    std::fprintf(stderr,
                 "truecut run: interrupted at %.6f s of the %.6f s asked for (--time); the "
                 "outputs hold the run up to there\n",
                 r.simulated_ns * 1e-9, limits.duration_ns * 1e-9);
  else if (limits.max_cycles > 0)
    std::fprintf(stderr,
                 "truecut run: interrupted after %llu of the %llu cycles asked for (--cycles); "
                 "the outputs hold the run up to there\n",
                 static_cast<unsigned long long>(fastest_thread_cycles(r)),
                 static_cast<unsigned long long>(limits.max_cycles));
}

// Removes the output folder at the end if this run created it and left it
// empty (a dry run, a configuration that failed to load).
struct OutputFolderGuard {
  std::filesystem::path dir;
  bool created;
  ~OutputFolderGuard() {
    std::error_code ec;
    if (created && std::filesystem::is_empty(dir, ec)) std::filesystem::remove(dir, ec);
  }
};

}  // namespace

int cmd_run(const std::vector<std::string>& argv) {
  // `truecut run MACHINE.json PROGRAM.ngc ...` machines a part (run_machine.cpp).
  if (machine_form(argv)) return run_machine(argv);
  ParsedArgs a(argv, {{"ini", true},
                      {"time", true},
                      {"cycles", true},
                      {"out", true},
                      {"component-path", true, true},
                      {"realtime", false},
                      {"cpu", true},
                      {"fifo", true},
                      {"no-mlock", false},
                      {"spin-us", true},
                      {"show", false},
                      {"dry-run", false},
                      kQuietOption,
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(kRunHelp, stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 1) throw UsageError("expected one CONFIG.hal file");
  const std::filesystem::path config = a.positionals()[0];
  const bool realtime = a.flag("realtime");
  if (!realtime && (a.value("cpu") || a.value("fifo") || a.flag("no-mlock") || a.value("spin-us")))
    throw UsageError("--cpu, --fifo, --no-mlock and --spin-us apply only with --realtime");
  if (a.value("time") && a.value("cycles")) throw UsageError("give --time or --cycles, not both");

  rt::hal::RunLimits limits;
  limits.duration_ns = static_cast<int64_t>(a.number("time", 0.0, 1e-6, 1e7) * 1e9 + 0.5);
  limits.max_cycles = static_cast<uint64_t>(a.integer("cycles", 0, 1, 2'000'000'000'000L));
  rt::hal::WallClockOptions wall;
  wall.cpu = static_cast<int>(a.integer("cpu", -1, 0, 1023));
  wall.fifo_priority = static_cast<int>(a.integer("fifo", 0, 1, 99));
  wall.lock_memory = !a.flag("no-mlock");
  wall.spin_ns = a.integer("spin-us", 0, 0, 100'000) * 1000;

  rt::hal::HalOptions opt;
  opt.component_path = component_path(a);
  opt.output_dir = a.value("out").value_or(".");
  opt.show_info_messages = !a.flag("quiet");

  std::optional<rt::hal::Ini> ini;
  try {
    if (auto f = a.value("ini")) ini = rt::hal::Ini::load(*f);
  } catch (const rt::hal::IniError& e) {
    std::fprintf(stderr, "truecut run: %s\n", e.what());
    return kExitUsage;
  }
  if (!std::filesystem::exists(config)) {
    std::fprintf(stderr, "truecut run: %s: no such file\n", config.c_str());
    return kExitUsage;
  }
  // A dry run loads the components too (a recorder creates its temporary
  // file at load), so it needs the folder; one it created is removed again.
  std::error_code ec;
  const bool dir_created = !std::filesystem::exists(opt.output_dir, ec);
  std::filesystem::create_directories(opt.output_dir, ec);
  if (ec) {
    std::fprintf(stderr, "truecut run: cannot create output folder %s: %s\n",
                 opt.output_dir.c_str(), ec.message().c_str());
    return kExitUsage;
  }
  const OutputFolderGuard folder{opt.output_dir, dir_created};

  rt::hal::Hal h(opt);
  try {
    rt::hal::load_hal_file(h, config, ini ? &*ini : nullptr);
  } catch (const rt::hal::HalFileError& e) {
    std::fprintf(stderr, "truecut run: %s\n", e.what());
    return kExitUsage;
  }
  if (h.threads().empty()) {
    std::fprintf(stderr, "truecut run: %s creates no thread (loadrt threads or newthread)\n",
                 config.c_str());
    return kExitUsage;
  }
  if (a.flag("show")) print_show(h);
  if (a.flag("dry-run")) {
    if (h.unload() > 0) return kExitFailure;
    std::printf("%s: configuration loads without error\n", config.c_str());
    return kExitOk;
  }

  Progress progress{limits.duration_ns};
  if (progress_shown(a)) {
    limits.progress = print_progress;
    limits.progress_user = &progress;
  }
  if (limits.duration_ns == 0 && limits.max_cycles == 0 && !a.flag("quiet"))
    std::fprintf(stderr, "running until a component stops or Ctrl-C (--time S to limit)\n");

  const InterruptibleRun run = run_interruptible(h, limits, realtime, wall);
  const rt::hal::RunReport& r = run.report;
  if (progress.last_ns >= 0) std::fputs("\n", stderr);

  std::printf("truecut run %s\n", config.c_str());
  std::printf("  mode        %s%s\n", r.wall_clock ? "wall clock" : "simulated time",
              r.stopped_by_request ? " (stopped on request)" : "");
  std::printf("  time        %.6f s simulated in %.3f s wall (%.1fx real time)\n",
              r.simulated_ns * 1e-9, r.wall_s,
              r.wall_s > 0 ? r.simulated_ns * 1e-9 / r.wall_s : 0.0);
  for (const auto& n : r.notes)
    std::printf("  setup       %s\n", n.c_str());
  for (const auto& t : r.threads) {
    std::printf("  thread      %s: period %lld ns, %llu cycles, %llu overruns\n", t.name.c_str(),
                (long long)t.period_ns, (unsigned long long)t.cycles,
                (unsigned long long)t.overruns);
    std::printf("    compute   median %s us, p99 %s us, p99.99 %s us, max %s us\n",
                us(t.compute.percentile_ns(0.5)).c_str(), us(t.compute.percentile_ns(0.99)).c_str(),
                us(t.compute.percentile_ns(0.9999)).c_str(), us(t.compute.max_ns()).c_str());
    if (r.wall_clock)
      std::printf("    latency   median %s us, p99 %s us, p99.99 %s us, max %s us\n",
                  us(t.latency.percentile_ns(0.5)).c_str(),
                  us(t.latency.percentile_ns(0.99)).c_str(),
                  us(t.latency.percentile_ns(0.9999)).c_str(), us(t.latency.max_ns()).c_str());
  }
  // The components write their files as they unload (recorder, cutting).
  if (const int errors = h.unload(); errors > 0) {
    std::fprintf(stderr,
                 "truecut run: %d output file(s) could not be written in full (see above)\n",
                 errors);
    return kExitFailure;
  }
  const bool limited = limits.duration_ns > 0 || limits.max_cycles > 0;
  if (run.interrupted && limited && !limit_reached(limits, r)) {
    report_interrupted_run(limits, r);
    return kExitInterrupted;
  }
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{"run", "run a .hal configuration in the soft-CNC executor",
                                        cmd_run, 10};
}  // namespace

}  // namespace truecut::cli
