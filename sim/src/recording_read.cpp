// Streamed reading of recording CSV files.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "line_reader.hpp"
#include "truecut/sim/recording.hpp"

namespace truecut::sim {
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

std::string shortest(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

bool parse_number(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
}

std::vector<Binding> bind_channels(const std::string& at, const std::vector<std::string>& columns,
                                   const RecordingOptions& options) {
  auto find = [&](const std::string& name) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == name) return i;
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
      b.source.column = channel;
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

RecordingHeader stream_recording(const std::filesystem::path& path, const RecordingOptions& options,
                                 const RowSink& sink) {
  const std::string file = path.string();
  detail::LineReader reader(path);
  RecordingHeader header;
  header.file = file;
  std::string line;
  std::vector<std::string> fields;
  while (reader.next(line)) {
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    detail::split_csv(line, fields);
    break;
  }
  if (fields.empty()) throw RecordingError(file + ": empty file, expected a header row");
  if (fields[0].rfind("\xEF\xBB\xBF", 0) == 0) fields[0].erase(0, 3);
  header.columns = fields;
  auto bindings =
      bind_channels(file + ":" + std::to_string(reader.line_number()), header.columns, options);
  for (const auto& b : bindings)
    header.channels.push_back(b.channel);

  std::vector<double> row(bindings.size());
  std::size_t index = 0;
  double last_t = 0;
  std::size_t last_t_line = 0;
  while (reader.next(line)) {
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    detail::split_csv(line, fields);
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
      if (!parse_number(fields[b.column], v))
        throw RecordingError(where() + ": '" + fields[b.column] + "' is not a finite number");
      row[k] = v * b.source.scale;
    }
    const double t = row[0];
    if (index > 0 && !(t > last_t))
      throw RecordingError(
          file + ":" + std::to_string(n) + ": column " +
          (bindings[0].source.from_index ? std::string("@index")
                                         : std::to_string(bindings[0].column + 1)) +
          " 't': time " + shortest(t) + " s is not after " + shortest(last_t) + " s on line " +
          std::to_string(last_t_line) + " (time must increase strictly)");
    last_t = t;
    last_t_line = n;
    sink(header, row);
    ++index;
  }
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

}  // namespace truecut::sim
