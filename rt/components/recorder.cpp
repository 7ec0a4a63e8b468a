// recorder: writes pins to a CSV trace, like LinuxCNC's sampler + halsampler.
//
//   loadrt recorder file=trace.csv columns=x_cmd,x_act,line:s32,on:bit
//                   [names=NAME] [every=N] [depth=N] [max-mb=N]
//
// One instance (`recorder.0` unless names= gives another name). Each column
// is an input pin `<inst>.<column>` (float unless suffixed :bit, :s32, :u32).
// The servo function `<inst>.sample` copies the pins and the cycle time into
// a lock-free queue every N-th cycle while `<inst>.enable` is true; a
// non-real-time service drains it into `<file>.tmp`, which becomes `<file>`
// when the HAL shuts down. `file` is a name inside the output folder (no
// absolute path, no '..'); /dev/null and FIFOs are written directly, from
// anywhere. The temporary file is created at load time, so a file that
// cannot be written fails the load. Samples that find the queue full are
// dropped and counted on `<inst>.overruns`. A trace that would grow beyond
// max-mb (default 65536 MB: a day at 1 kHz of every soft-CNC column) stops
// there, asks the executor to stop and reports an error at unload; the
// lines written until then are kept.
#include <algorithm>
#include <boost/lockfree/spsc_queue.hpp>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "builtin_components.hpp"
#include "truecut/rt/component_support.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"

namespace truecut::rt::hal::builtin {
namespace {

constexpr int kMaxColumns = 64;
constexpr long kDefaultMaxMb = 65536;
constexpr long kMaxMaxMb = 1L << 30;  // 1 PB

struct Sample {
  int64_t t_ns;
  double v[kMaxColumns];
};

struct Column {
  std::string name;
  tc_hal_type_t type;
  void* pin;  // aimed by the HAL
};

struct Recorder {
  std::string instance;
  std::filesystem::path final_path;
  std::filesystem::path tmp_path;
  std::vector<Column> columns;
  uint32_t every = 1;
  std::unique_ptr<boost::lockfree::spsc_queue<Sample>> queue;
  // Servo-side state.
  bool* enable = nullptr;
  uint32_t* overruns = nullptr;
  uint32_t* samples = nullptr;
  int64_t t_ns = 0;
  uint64_t cycle = 0;
  // Service-side state.
  std::unique_ptr<PendingFile> pending;  // the .tmp file, removed on SIGINT/SIGTERM
  std::FILE* out = nullptr;
  bool direct = false;  // writing straight into /dev/null or a FIFO, no rename
  bool header_written = false;
  bool write_failed = false;
  uint64_t max_bytes = 0;
  uint64_t written_bytes = 0;
  long max_mb = 0;
  bool size_limit_reached = false;
  double last_written_t_s = 0;
  std::string line;
  const tc_hal_api_t* api = nullptr;
  tc_hal_t* hal = nullptr;
};

double read_pin(const Column& c) {
  switch (c.type) {
    case TC_HAL_BIT:
      return *static_cast<const bool*>(c.pin) ? 1.0 : 0.0;
    case TC_HAL_S32:
      return *static_cast<const int32_t*>(c.pin);
    case TC_HAL_U32:
      return *static_cast<const uint32_t*>(c.pin);
    case TC_HAL_FLOAT:
      return *static_cast<const double*>(c.pin);
  }
  return 0.0;
}

void sample(void* arg, long period_ns) {
  auto& r = *static_cast<Recorder*>(arg);
  const int64_t t = r.t_ns;
  r.t_ns += period_ns;
  if (r.cycle++ % r.every != 0 || !*r.enable) return;
  Sample s;
  s.t_ns = t;
  const size_t n = r.columns.size();
  for (size_t i = 0; i < n; ++i)
    s.v[i] = read_pin(r.columns[i]);
  if (r.queue->push(s))
    ++*r.samples;
  else
    ++*r.overruns;
}

void append_number(std::string& line, double v) {
  char buf[32];
  auto res = std::to_chars(buf, buf + sizeof buf, v);
  line.append(buf, res.ptr);
}

std::string size_limit_text(const Recorder& r) {
  char t[32];
  std::snprintf(t, sizeof t, "%.6g", r.last_written_t_s);
  return r.instance + ": " + r.final_path.string() +
         " reached its size limit max-mb=" + std::to_string(r.max_mb) +
         " (MB); the run is stopped and the trace ends at t = " + t +
         " s (loadrt recorder ... max-mb=N raises the limit)";
}

void drain(void* arg) {
  auto& r = *static_cast<Recorder*>(arg);
  Sample s;
  while (r.queue->pop(s)) {
    if (r.write_failed || r.size_limit_reached) continue;
    if (!r.out) {
      // A FIFO is opened on first use: opening it waits for its reader.
      r.out = std::fopen(r.final_path.c_str(), "wb");
      if (!r.out) {
        r.write_failed = true;
        r.api->message(
            r.hal, TC_HAL_MSG_ERR,
            ("recorder: cannot open " + r.final_path.string() + ": " + std::strerror(errno))
                .c_str());
        continue;
      }
    }
    if (!r.header_written) {
      r.header_written = true;
      r.line = "t";
      for (const auto& c : r.columns)
        r.line += "," + c.name;
      r.line += "\n";
      std::fputs(r.line.c_str(), r.out);
      r.written_bytes += r.line.size();
    }
    r.line.clear();
    // Time from the integer cycle clock, so it never accumulates rounding.
    append_number(r.line, double(s.t_ns) * 1e-9);
    for (size_t i = 0; i < r.columns.size(); ++i) {
      r.line += ',';
      append_number(r.line, s.v[i]);
    }
    r.line += '\n';
    if (r.written_bytes + r.line.size() > r.max_bytes) {
      r.size_limit_reached = true;
      r.api->request_stop(r.hal);
      r.api->message(r.hal, TC_HAL_MSG_ERR, size_limit_text(r).c_str());
      continue;
    }
    if (std::fputs(r.line.c_str(), r.out) < 0) r.write_failed = true;
    r.written_bytes += r.line.size();
    r.last_written_t_s = double(s.t_ns) * 1e-9;
  }
}

// Counted before any name is parsed: the duplicate check below compares
// each name with the ones before it.
void check_column_count(const std::string& spec) {
  const std::size_t count = 1 + static_cast<std::size_t>(std::count(spec.begin(), spec.end(), ','));
  if (count > kMaxColumns)
    throw component::InitError("columns= lists " + std::to_string(count) + " columns, at most " +
                               std::to_string(kMaxColumns));
}

std::vector<Column> parse_columns(const std::string& spec) {
  check_column_count(spec);
  std::vector<Column> cols;
  std::string cur;
  for (char c : spec + ",") {
    if (c != ',') {
      cur += c;
      continue;
    }
    if (cur.empty()) throw component::InitError("columns='" + spec + "' has an empty column");
    Column col{cur, TC_HAL_FLOAT, nullptr};
    if (auto colon = cur.find(':'); colon != std::string::npos) {
      std::string t = cur.substr(colon + 1);
      col.name = cur.substr(0, colon);
      if (t == "bit")
        col.type = TC_HAL_BIT;
      else if (t == "s32")
        col.type = TC_HAL_S32;
      else if (t == "u32")
        col.type = TC_HAL_U32;
      else if (t == "float")
        col.type = TC_HAL_FLOAT;
      else
        throw component::InitError("column '" + cur + "': type must be bit, s32, u32 or float");
    }
    if (col.name == "t") throw component::InitError("column name 't' is reserved for time");
    for (const auto& other : cols)
      if (other.name == col.name) throw component::InitError("column '" + col.name + "' twice");
    cols.push_back(col);
    cur.clear();
  }
  return cols;
}

}  // namespace

int recorder_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc, const char* const* argv,
                  void** state) {
  using namespace component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto names = instance_names(args, "recorder", 1);
    auto file = args.take("file");
    auto columns = args.take("columns");
    const long every = args.take_long("every", 1, 1, 1'000'000);
    const long depth = args.take_long("depth", 8192, 16, 1 << 20);
    const long max_mb = args.take_long("max-mb", kDefaultMaxMb, 1, kMaxMaxMb);
    args.expect_consumed("recorder");
    if (!file) throw InitError("file= is required (e.g. file=trace.csv)");
    if (!columns) throw InitError("columns= is required (e.g. columns=x_cmd,x_act)");

    auto r = std::make_unique<Recorder>();
    r->instance = names.at(0);
    const std::filesystem::path named(*file);
    r->final_path =
        named.is_absolute() ? named : std::filesystem::path(api->output_dir(hal)) / named;
    // /dev/null and FIFOs are written directly (renaming a temporary file
    // over one would replace it), and may be named anywhere.
    std::error_code ec;
    r->direct = r->final_path == "/dev/null" ||
                std::filesystem::is_fifo(std::filesystem::status(r->final_path, ec));
    bool outside = named.is_absolute();
    for (const auto& part : named)
      outside = outside || part == "..";
    if (outside && !r->direct)
      throw InitError("file=" + *file +
                      ": outside the output folder; a recorder writes a name inside it (no "
                      "absolute path, no '..'), /dev/null or a FIFO");
    r->tmp_path = r->final_path;
    r->tmp_path += ".tmp";
    r->columns = parse_columns(*columns);
    r->every = static_cast<uint32_t>(every);
    r->max_mb = max_mb;
    r->max_bytes = static_cast<uint64_t>(max_mb) * 1'000'000u;
    r->queue = std::make_unique<boost::lockfree::spsc_queue<Sample>>(static_cast<size_t>(depth));
    r->api = api;
    r->hal = hal;

    const std::string& n = r->instance;
    int id = new_component(api, hal, n);
    Builder b(api, hal, id);
    for (auto& c : r->columns)
      b.pin(n + "." + c.name, c.type, TC_HAL_IN, &c.pin);
    b.pin(n + ".enable", TC_HAL_BIT, TC_HAL_IN, &r->enable);
    b.pin(n + ".overruns", TC_HAL_U32, TC_HAL_OUT, &r->overruns);
    b.pin(n + ".samples", TC_HAL_U32, TC_HAL_OUT, &r->samples);
    *r->enable = true;
    b.funct(n + ".sample", sample, r.get());
    b.service(drain, r.get());
    // Last in init: from here on recorder_exit removes it again.
    if (!r->direct) {
      r->pending = std::make_unique<PendingFile>(r->tmp_path);
      r->out = std::fopen(r->tmp_path.c_str(), "wb");
      if (!r->out)
        throw InitError("file=" + *file + ": cannot create " + r->tmp_path.string() + ": " +
                        std::strerror(errno));
    }
    api->component_ready(hal, id);
    *state = r.release();
    return 0;
  });
}

void recorder_exit(const tc_hal_api_t* api, tc_hal_t* hal, void* state) {
  std::unique_ptr<Recorder> r(static_cast<Recorder*>(state));
  if (!r) return;
  drain(r.get());
  std::error_code ec;
  if (!r->header_written) {  // no sample: no file at all
    if (r->out) std::fclose(r->out);
    if (!r->direct) std::filesystem::remove(r->tmp_path, ec);
    if (r->write_failed)
      api->message(hal, TC_HAL_MSG_ERR,
                   ("recorder: " + r->final_path.string() + " not written").c_str());
    return;
  }
  bool ok = !r->write_failed;
  if (std::fclose(r->out) != 0) ok = false;
  if (ok && !r->direct) std::filesystem::rename(r->tmp_path, r->final_path, ec);
  if (!ok || ec) {
    if (!r->direct) std::filesystem::remove(r->tmp_path, ec);
    api->message(
        hal, TC_HAL_MSG_ERR,
        ("recorder: writing " + r->final_path.string() + " failed; no trace written").c_str());
    return;
  }
  if (r->size_limit_reached) {
    // Counted as an error of the unload: the run does not end with 0 on a
    // trace that stops short.
    api->message(hal, TC_HAL_MSG_ERR,
                 (size_limit_text(*r) + "; " + std::to_string(r->written_bytes) +
                  " bytes kept, the samples after it dropped")
                     .c_str());
    return;
  }
  api->message(hal, TC_HAL_MSG_INFO,
               (r->instance + ": wrote " + std::to_string(*r->samples) + " samples to " +
                r->final_path.string())
                   .c_str());
  if (*r->overruns > 0)
    api->message(hal, TC_HAL_MSG_WARN,
                 (std::to_string(*r->overruns) + " samples dropped (queue full) in " +
                  r->final_path.string())
                     .c_str());
}

}  // namespace truecut::rt::hal::builtin
