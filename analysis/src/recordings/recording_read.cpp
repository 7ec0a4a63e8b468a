// Streamed reading of recording CSV files.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <string_view>

#include "channel_range.hpp"
#include "line_reader.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis {
namespace {

struct Binding {
  std::string channel;
  ChannelSource source;
  std::size_t column = 0;  // index into the header; unused when from_index
};

std::string available(const std::vector<std::string>& columns) {
  std::string s;
  for (const auto& c : columns)
    s += (s.empty() ? "" : ", ") + c;
  return s.empty() ? "(none)" : s;
}

bool parse_number(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
}

// A header name split into its name and a unit written after it in
// brackets or parentheses: "x_cmd [um]" -> ("x_cmd", "um").
struct HeaderName {
  std::string name, unit;
};

HeaderName split_unit(const std::string& column) {
  std::string c = column;
  while (!c.empty() && c.back() == ' ')
    c.pop_back();
  if (c.size() >= 3 && (c.back() == ']' || c.back() == ')')) {
    const char open = c.back() == ']' ? '[' : '(';
    const auto at = c.rfind(open);
    if (at != std::string::npos && at > 0) {
      std::string name = c.substr(0, at), unit = c.substr(at + 1, c.size() - at - 2);
      while (!name.empty() && (name.back() == ' ' || name.back() == '_' || name.back() == '/'))
        name.pop_back();
      auto trim = [](std::string v) {
        while (!v.empty() && v.front() == ' ')
          v.erase(v.begin());
        while (!v.empty() && v.back() == ' ')
          v.pop_back();
        return v;
      };
      return {name, trim(unit)};
    }
  }
  return {c, ""};
}

std::string lower(std::string s) {
  for (char& ch : s)
    ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

// The factor taking `unit` to the canonical unit of `channel` (s, mm, deg,
// mm/s, kW); nullopt when the unit is not one of that kind.
std::optional<double> unit_factor(const std::string& channel, const std::string& unit_text) {
  std::string u = lower(unit_text);
  for (const char* micro : {"\xC2\xB5", "\xCE\xBC"})  // µ (micro sign), μ (Greek mu)
    if (u.rfind(micro, 0) == 0) u = "u" + u.substr(2);
  if (u == "\xC2\xB0") u = "deg";  // °
  const std::map<std::string, double> time{{"s", 1},     {"sec", 1},  {"ms", 1e-3},
                                           {"us", 1e-6}, {"min", 60}, {"h", 3600}};
  const std::map<std::string, double> length{{"mm", 1},    {"um", 1e-3},   {"micron", 1e-3},
                                             {"nm", 1e-6}, {"cm", 10},     {"m", 1000},
                                             {"in", 25.4}, {"inch", 25.4}, {"mil", 0.0254}};
  const std::map<std::string, double> angle{{"deg", 1},
                                            {"degree", 1},
                                            {"degrees", 1},
                                            {"rad", 180.0 / 3.14159265358979323846},
                                            {"mrad", 0.18 / 3.14159265358979323846},
                                            {"arcmin", 1.0 / 60},
                                            {"arcsec", 1.0 / 3600}};
  const std::map<std::string, double> speed{
      {"mm/s", 1},           {"mm/min", 1.0 / 60}, {"m/min", 1000.0 / 60},
      {"in/min", 25.4 / 60}, {"ipm", 25.4 / 60},   {"um/s", 1e-3}};
  const std::map<std::string, double> power{{"kw", 1}, {"w", 1e-3}};
  const std::map<std::string, double>* table = nullptr;
  const bool joint = channel.size() > 2 && channel[1] == '_';
  if (channel == "t")
    table = &time;
  else if (joint && is_rotary_joint(channel.substr(0, 1)))
    table = &angle;
  else if (joint || channel.rfind("tcp_true_", 0) == 0)
    table = &length;
  else if (channel == "feed")
    table = &speed;
  else if (channel == "spindle_power")
    table = &power;
  if (!table) return std::nullopt;
  const auto it = table->find(u);
  if (it == table->end()) return std::nullopt;
  return it->second;
}

const char* unit_of(const std::string& channel) {
  const bool joint = channel.size() > 2 && channel[1] == '_';
  if (channel == "t") return "s";
  if (joint && is_rotary_joint(channel.substr(0, 1))) return "deg";
  if (joint || channel.rfind("tcp_true_", 0) == 0) return "mm";
  if (channel == "feed") return "mm/s";
  if (channel == "spindle_power") return "kW";
  return "no unit";
}

std::vector<Binding> bind_channels(const std::string& at, const std::vector<std::string>& columns,
                                   const RecordingOptions& options) {
  std::vector<HeaderName> names;
  for (const auto& c : columns)
    names.push_back(split_unit(c));
  // The column called `name`: exactly, else without its unit, else ignoring
  // case (without the unit); an ambiguous match is an error.
  auto find = [&](const std::string& name) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      if (columns[i] != name) continue;
      // The same name twice is an ambiguous channel: which column holds it?
      for (std::size_t k = i + 1; k < columns.size(); ++k)
        if (columns[k] == name)
          throw RecordingError(at + ": columns " + std::to_string(i + 1) + " and " +
                               std::to_string(k + 1) + " are both named '" + name +
                               "': an ambiguous channel; remove or rename one of them");
      return i;
    }
    for (const bool fold : {false, true}) {
      std::optional<std::size_t> hit;
      for (std::size_t i = 0; i < columns.size(); ++i) {
        const bool same = fold ? lower(names[i].name) == lower(name) : names[i].name == name;
        if (!same) continue;
        if (hit)
          throw RecordingError(at + ": columns " + std::to_string(*hit + 1) + " '" + columns[*hit] +
                               "' and " + std::to_string(i + 1) + " '" + columns[i] +
                               "' both match '" + name + "'; name the one meant with --map");
        hit = i;
      }
      if (hit) return hit;
    }
    return std::nullopt;
  };
  std::vector<Binding> out;
  for (const auto& channel : canonical_channels()) {
    Binding b{channel, {}, 0};
    if (auto m = options.map.find(channel); m != options.map.end()) {
      b.source = m->second;
      if (!b.source.from_index) {
        auto i = find(b.source.column);
        if (!i)
          throw RecordingError(at + ": --map " + channel + "=" + b.source.column + ": no column '" +
                               b.source.column +
                               "' in the header; available: " + available(columns));
        b.column = *i;
      }
    } else if (auto i = find(channel)) {
      b.source.column = columns[*i];
      b.column = *i;
    } else {
      if (channel == "t")
        throw RecordingError(at +
                             ": no time column 't'; map one (--map t=COLUMN) or "
                             "synthesise it from the row index (--map t=@index*PERIOD_S); "
                             "available: " +
                             available(columns));
      continue;
    }
    // A unit in the header converts the values, unless the map gave a factor.
    if (!b.source.from_index && !b.source.factor_given) {
      const std::string& unit = names[b.column].unit;
      if (!unit.empty()) {
        const auto f = unit_factor(channel, unit);
        if (!f)
          throw RecordingError(at + ": column " + std::to_string(b.column + 1) + " '" +
                               columns[b.column] + "' (" + channel + "): unit '" + unit +
                               "' is not one for " + channel + " (" + unit_of(channel) +
                               "); give the factor to " + unit_of(channel) + " with --map " +
                               channel + "=" + columns[b.column] + "*FACTOR");
        b.source.scale = *f;
      }
    }
    out.push_back(b);
  }
  for (const auto& r : options.required) {
    bool found = false;
    for (const auto& b : out)
      found = found || b.channel == r;
    if (!found)
      throw RecordingError(at + ": no column for '" + r + "' (name a column '" + r +
                           "' or map one with --map " + r +
                           "=COLUMN); available: " + available(columns));
  }
  return out;
}

}  // namespace

namespace detail {

namespace {
// What a value of a channel may be, and why: beyond these a value is a unit
// mix-up or a corrupt row, and the fits downstream overflow on it (1e154
// squared is inf).
struct ChannelRange {
  double limit;  // |value| <= limit
  const char* why;
};
ChannelRange plausible_range(const std::string& channel) {
  const std::string unit = unit_of(channel);
  if (unit == "s") return {1e9, "a recording of more than 31 years"};
  if (unit == "deg") return {1e7, "more than 27,778 turns"};
  if (unit == "mm") return {1e5, "no machine is larger than 100 m"};
  if (unit == "mm/s") return {1e6, "a feed over 1 km/s"};
  if (unit == "kW") return {1e4, "a spindle over 10 MW"};
  return {1e9, "a line or tool number over 1e9"};
}

}  // namespace

std::string implausible_value(const std::string& channel, double value) {
  const ChannelRange r = plausible_range(channel);
  if (std::fabs(value) <= r.limit) return "";
  return rt::format_shortest(value) + " " + unit_of(channel) + " is outside -" +
         rt::format_shortest(r.limit) + " .. " + rt::format_shortest(r.limit) + " (" + r.why +
         "; check the unit or the --map factor)";
}

}  // namespace detail

RecordingHeader stream_recording(const std::filesystem::path& path, const RecordingOptions& options,
                                 const RowSink& sink) {
  const std::string file = path.string();
  detail::LineReader reader(path);
  RecordingHeader header;
  header.file = file;
  std::string line;
  std::vector<std::string> fields;
  // Blank lines and comment lines ('#' first) carry no data.
  auto skipped = [](const std::string& l) {
    const auto first = l.find_first_not_of(" \t");
    return first == std::string::npos || l[first] == '#';
  };
  char delimiter = ',';
  bool first_line = true;
  while (reader.next(line)) {
    if (first_line && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    first_line = false;
    if (skipped(line)) continue;
    delimiter = detail::detect_delimiter(line);
    detail::split_csv(line, fields, delimiter);
    break;
  }
  if (fields.empty()) throw RecordingError(file + ": empty file, expected a header row");
  header.columns = fields;
  auto bindings =
      bind_channels(file + ":" + std::to_string(reader.line_number()), header.columns, options);
  for (const auto& b : bindings)
    header.channels.push_back(b.channel);

  std::vector<double> row(bindings.size());
  std::size_t index = 0;
  double last_t = 0;
  std::size_t last_t_line = 0;
  std::string cell;
  while (reader.next(line)) {
    if (skipped(line)) continue;
    detail::split_csv(line, fields, delimiter);
    const std::size_t n = reader.line_number();
    for (std::size_t k = 0; k < bindings.size(); ++k) {
      const Binding& b = bindings[k];
      if (b.source.from_index) {
        row[k] = double(index) * b.source.scale;
        continue;
      }
      auto where = [&] {
        return file + ":" + std::to_string(n) + ": column " + std::to_string(b.column + 1) + " '" +
               header.columns[b.column] + "'" +
               (b.channel != header.columns[b.column] ? " (" + b.channel + ")" : "");
      };
      if (b.column >= fields.size())
        throw RecordingError(where() + ": missing; the row has " + std::to_string(fields.size()) +
                             " fields, the header " + std::to_string(header.columns.size()));
      double v = 0;
      const std::string* text = &fields[b.column];
      if (delimiter == ';' && text->find(',') != std::string::npos &&
          text->find('.') == std::string::npos) {
        cell = *text;  // a decimal comma
        std::replace(cell.begin(), cell.end(), ',', '.');
        text = &cell;
      }
      if (!parse_number(*text, v))
        throw RecordingError(where() + ": '" + fields[b.column] + "' is not a finite number");
      row[k] = v * b.source.scale;
      if (const std::string bad = detail::implausible_value(b.channel, row[k]); !bad.empty())
        throw RecordingError(where() + ": " + bad);
    }
    const double t = row[0];
    if (index > 0 && !(t > last_t))
      throw RecordingError(file + ":" + std::to_string(n) + ": column " +
                           (bindings[0].source.from_index
                                ? std::string("@index")
                                : std::to_string(bindings[0].column + 1)) +
                           " 't': time " + rt::format_shortest(t) + " s is not after " +
                           rt::format_shortest(last_t) + " s on line " +
                           std::to_string(last_t_line) + " (time must increase strictly)");
    last_t = t;
    last_t_line = n;
    sink(header, row);
    ++index;
  }
  if (index == 0) throw RecordingError(file + ": a header and no data rows");
  return header;
}

const std::vector<double>& Recording::channel(const std::string& name) const {
  if (name == "t") return t_s;
  auto it = channels.find(name);
  if (it == channels.end()) {
    std::string present = "t";
    for (const auto& [k, v] : channels)
      present += ", " + k;
    throw RecordingError(file + ": no channel '" + name + "'; the recording has: " + present);
  }
  return it->second;
}

const std::vector<double>* Recording::measured(const std::string& joint) const {
  if (auto it = channels.find(joint + "_meas"); it != channels.end()) return &it->second;
  if (auto it = channels.find(joint + "_act"); it != channels.end()) return &it->second;
  return nullptr;
}

Recording read_recording(const std::filesystem::path& file, const RecordingOptions& options) {
  Recording rec;
  rec.file = file.string();
  std::vector<std::vector<double>*> targets;
  auto header = stream_recording(file, options,
                                 [&](const RecordingHeader& h, const std::vector<double>& row) {
                                   if (targets.empty()) {
                                     targets.push_back(&rec.t_s);
                                     for (std::size_t k = 1; k < h.channels.size(); ++k)
                                       targets.push_back(&rec.channels[h.channels[k]]);
                                   }
                                   for (std::size_t k = 0; k < row.size(); ++k)
                                     targets[k]->push_back(row[k]);
                                 });
  rec.columns = header.columns;
  for (std::size_t k = 1; k < header.channels.size(); ++k)
    rec.channels[header.channels[k]];
  return rec;
}

}  // namespace truecut::analysis
