// EPICS camonitor logs as recordings (docs/formats.md, "camonitor logs").
//
// A line is `PV DATE TIME VALUE [STATUS SEVERITY]`, one per change of one
// process variable, so the channels come at their own, irregular times. The
// first lines of a log carry each PV's value as of its last change, which
// may be long before the log began. The events are put in time order and
// every mapped channel is held at its last value; a row is written at every
// time stamp once every mapped channel has a value.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>

#include "channel_range.hpp"
#include "line_reader.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis {
namespace {

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
      ++i;
    const std::size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t')
      ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

bool digits(std::string_view s, std::size_t at, std::size_t n, int& v) {
  if (at + n > s.size()) return false;
  v = 0;
  for (std::size_t k = at; k < at + n; ++k) {
    if (s[k] < '0' || s[k] > '9') return false;
    v = v * 10 + (s[k] - '0');
  }
  return true;
}

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's algorithm).
std::int64_t days_from_civil(int y, int m, int d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = unsigned(y - era * 400);
  const unsigned doy = unsigned((153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1);
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + std::int64_t(doe) - 719468;
}

int days_in_month(int y, int m) {
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  return m == 2 && leap ? 29 : kDays[m - 1];
}

bool is_date(std::string_view s) {
  int v = 0;
  return s.size() == 10 && digits(s, 0, 4, v) && s[4] == '-' && digits(s, 5, 2, v) && s[7] == '-' &&
         digits(s, 8, 2, v);
}

bool is_time(std::string_view s) {
  int v = 0;
  return s.size() >= 8 && digits(s, 0, 2, v) && s[2] == ':' && digits(s, 3, 2, v) && s[5] == ':' &&
         digits(s, 6, 2, v);
}

// Seconds since 1970-01-01 00:00:00 of "YYYY-MM-DD" "HH:MM:SS[.ffffff]".
bool parse_stamp(std::string_view date, std::string_view time, double& seconds) {
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, s = 0;
  if (!is_date(date) || !is_time(time)) return false;
  digits(date, 0, 4, y);
  digits(date, 5, 2, mo);
  digits(date, 8, 2, d);
  digits(time, 0, 2, h);
  digits(time, 3, 2, mi);
  digits(time, 6, 2, s);
  if (mo < 1 || mo > 12 || d < 1 || d > days_in_month(y, mo) || h > 23 || mi > 59 || s > 60)
    return false;
  double fraction = 0;
  if (time.size() > 8) {
    if (time[8] != '.' || time.size() == 9) return false;
    double scale = 0.1;
    for (std::size_t k = 9; k < time.size(); ++k) {
      if (time[k] < '0' || time[k] > '9') return false;
      fraction += (time[k] - '0') * scale;
      scale /= 10;
    }
  }
  seconds = double(days_from_civil(y, mo, d)) * 86400.0 + h * 3600.0 + mi * 60.0 + s + fraction;
  return true;
}

bool parse_number(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
}

struct Event {
  double time;
  std::size_t channel;
  double value;
};

// A time stamp and where it was read, for the span check.
struct Stamp {
  double time = 0;
  std::size_t line = 0;
  std::string text;
};

std::string list(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names)
    s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "(none)" : s;
}

}  // namespace

bool is_camonitor_log(const std::filesystem::path& file) {
  detail::LineReader in(file);
  std::string line;
  while (in.next(line)) {
    const auto tok = tokens(line);
    if (tok.empty() || tok[0].front() == '#') continue;
    if (tok.size() >= 3 && tok[1] == "<undefined>") return true;
    return tok.size() >= 4 && is_date(tok[1]) && is_time(tok[2]);
  }
  return false;
}

Recording read_camonitor(const std::filesystem::path& file, const RecordingOptions& options) {
  const std::string name = file.string();
  // Mapped channels: PV name → channel indices (one PV may feed several).
  std::vector<std::string> channels;
  std::vector<double> scales;
  std::map<std::string, std::vector<std::size_t>> by_pv;
  for (const auto& [channel, src] : options.map) {
    if (channel == "t")
      throw RecordingError(name + ": --map t=...: a camonitor log carries its own time stamps");
    if (src.from_index)
      throw RecordingError(name + ": --map " + channel +
                           "=@index: a camonitor log has no row index; map a PV name");
    by_pv[src.column].push_back(channels.size());
    channels.push_back(channel);
    scales.push_back(src.scale);
  }

  detail::LineReader in(file);
  std::string line;
  std::vector<Event> events;
  std::optional<Stamp> earliest, latest;
  std::vector<std::string> pvs;  // every PV of the log, in order of appearance
  std::set<std::string> seen;
  while (in.next(line)) {
    const auto tok = tokens(line);
    if (tok.empty() || tok[0].front() == '#') continue;
    const std::string pv(tok[0]);
    if (seen.insert(pv).second) pvs.push_back(pv);
    const auto it = by_pv.find(pv);
    if (it == by_pv.end()) continue;  // not mapped: may hold anything
    auto where = [&] {
      std::ostringstream s;
      s << name << ":" << in.line_number() << ": PV '" << pv << "'";
      return s.str();
    };
    // No time stamp yet, or a connection notice: no value.
    if (tok.size() >= 2 && (tok[1] == "<undefined>" || tok[1].rfind("***", 0) == 0)) continue;
    if (tok.size() < 4)
      throw RecordingError(where() + ": expected 'PV DATE TIME VALUE', got '" + line + "'");
    double time = 0, value = 0;
    if (!parse_stamp(tok[1], tok[2], time))
      throw RecordingError(where() + ": bad time stamp '" + std::string(tok[1]) + " " +
                           std::string(tok[2]) +
                           "' (expected a date and time that exist, YYYY-MM-DD HH:MM:SS.ffffff)");
    if (!parse_number(tok[3], value))
      throw RecordingError(where() + ": value '" + std::string(tok[3]) + "' is not a number");
    const std::string stamp_text = std::string(tok[1]) + " " + std::string(tok[2]);
    if (!earliest || time < earliest->time) earliest = Stamp{time, in.line_number(), stamp_text};
    if (!latest || time > latest->time) latest = Stamp{time, in.line_number(), stamp_text};
    for (std::size_t c : it->second) {
      if (const std::string bad = detail::implausible_value(channels[c], value * scales[c]);
          !bad.empty())
        throw RecordingError(where() + ": " + bad);
      events.push_back({time, c, value * scales[c]});
    }
  }

  Recording rec;
  rec.file = name;
  rec.columns = pvs;
  for (const auto& req : options.required) {
    if (std::find(channels.begin(), channels.end(), req) != channels.end()) continue;
    throw RecordingError(name + ": no PV mapped to '" + req + "' (map one with --map " + req +
                         "=PV); PVs in the log: " + list(pvs));
  }
  for (const auto& [pv, chans] : by_pv)
    if (!seen.count(pv))
      throw RecordingError(name + ": --map " + channels[chans.front()] + "=" + pv +
                           ": the log has no PV '" + pv + "'; PVs in the log: " + list(pvs));

  // Times are taken from the first row; a recording spans at most the
  // recording readers' 1e9 s (a year 9999 among 2022's stamps gave 2.5e11 s).
  if (earliest && latest) {
    const std::string bad = detail::implausible_value("t", latest->time - earliest->time);
    if (!bad.empty())
      throw RecordingError(
          name + ":" + std::to_string(latest->line) + ": time stamp '" + latest->text + "' is " +
          rt::format_shortest(latest->time - earliest->time) + " s after the stamp '" +
          earliest->text + "' on line " + std::to_string(earliest->line) +
          ": a recording spans at most 1e9 s ("
          "31 years); check the dates");
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.time < b.time; });
  std::vector<double> value(channels.size(), 0.0);
  std::vector<bool> known(channels.size(), false);
  std::size_t missing = channels.size();
  std::vector<std::vector<double>> columns(channels.size());
  double t0 = 0;
  for (std::size_t k = 0; k < events.size();) {
    const double time = events[k].time;
    for (; k < events.size() && events[k].time == time; ++k) {
      const auto& e = events[k];
      if (!known[e.channel]) known[e.channel] = true, --missing;
      value[e.channel] = e.value;
    }
    if (missing > 0) continue;
    if (rec.t_s.empty()) t0 = time;
    rec.t_s.push_back(time - t0);
    for (std::size_t c = 0; c < channels.size(); ++c)
      columns[c].push_back(value[c]);
  }
  if (rec.t_s.empty() && !channels.empty())
    throw RecordingError(name + ": no time at which every mapped PV (" + list(channels) +
                         ") has a value");
  for (std::size_t c = 0; c < channels.size(); ++c)
    rec.channels[channels[c]] = std::move(columns[c]);
  return rec;
}

}  // namespace truecut::analysis
