// Recordings (DESIGN.md, Contracts → Recordings): a CSV trace with a header
// row, `t` in seconds and per-joint `<j>_cmd`, `<j>_act`, optional `<j>_meas`
// channels, read in a streamed pass. Foreign files are read through a column
// map (docs/formats.md, "Trace CSV (recordings)") instead of being edited.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace truecut::analysis {

// Joints a recording may carry, in contract order.
inline constexpr const char* kRecordingJoints[] = {"x", "y", "z", "a", "c"};
bool is_rotary_joint(const std::string& joint);  // a, c: degrees

// Canonical channel names a column may be mapped to: t, <j>_cmd, <j>_act,
// <j>_meas, feed, spindle_power, line, tool.
bool is_canonical_channel(const std::string& name);
std::vector<std::string> canonical_channels();

// Where one canonical channel comes from: a header column scaled by
// `scale`, or the data-row index times `scale` (`@index*PERIOD`).
struct ChannelSource {
  std::string column;  // empty when from_index
  bool from_index = false;
  double scale = 1.0;
  bool factor_given = false;  // `*FACTOR` was written: a unit in the header is not applied
};

// NAME=SOURCE[,NAME=SOURCE...]; see docs/formats.md. Throws RecordingError
// naming the offending item.
using ColumnMap = std::map<std::string, ChannelSource>;
ColumnMap parse_column_map(const std::string& spec);

// All problems with a recording: "FILE:LINE: column N 'NAME': what".
struct RecordingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct RecordingOptions {
  ColumnMap map;
  // Channels that must be present (besides t); a missing one is an error
  // that lists the available columns.
  std::vector<std::string> required;
};

// One row as delivered to a streaming consumer: values in the order of
// RecordingHeader::channels.
struct RecordingHeader {
  std::string file;
  std::vector<std::string> channels;  // canonical names, t first
  std::vector<std::string> columns;   // every header column of the file
};

using RowSink = std::function<void(const RecordingHeader&, const std::vector<double>& row)>;

// Reads the file once, in chunks, calling `sink` per data row. CR, LF and
// CRLF line endings are accepted; blank lines and lines starting with '#'
// are skipped; the delimiter is the header's most frequent of ',' ';' and
// tab (with ';' a decimal comma is accepted). A header name may carry a unit
// in brackets or parentheses ("x_cmd [um]", "t (ms)"): the values are
// converted to the channel's unit (s, mm, deg, mm/s, kW); names are matched
// exactly, then without the unit, then ignoring case. Only mapped or
// canonically named columns are parsed; other columns may hold anything.
// Returns the header; throws RecordingError.
RecordingHeader stream_recording(const std::filesystem::path& file, const RecordingOptions& options,
                                 const RowSink& sink);

// A whole recording in memory: one vector per canonical channel.
struct Recording {
  std::string file;
  std::vector<double> t_s;
  std::map<std::string, std::vector<double>> channels;  // without t
  std::vector<std::string> columns;                     // header of the file

  std::size_t rows() const { return t_s.size(); }
  bool has(const std::string& channel) const { return channels.count(channel) > 0; }
  // Throws RecordingError naming the file and the channels present.
  const std::vector<double>& channel(const std::string& name) const;
  // `<j>_meas` when present, else `<j>_act`; nullptr when neither.
  const std::vector<double>* measured(const std::string& joint) const;
};

Recording read_recording(const std::filesystem::path& file, const RecordingOptions& options = {});

// EPICS camonitor logs (docs/formats.md, "camonitor logs"): one line
// `PV YYYY-MM-DD HH:MM:SS.ffffff VALUE [STATUS SEVERITY]` per change of one
// process variable, each PV at its own irregular times. True when the
// first line that is not blank or '#' has that form.
bool is_camonitor_log(const std::filesystem::path& file);
// Channels come from `options.map` (NAME=PV or NAME=PV*FACTOR; `t` and
// `@index` are refused). The events are put in time order (the first lines
// of a log may carry older time stamps) and every channel is held at its
// last value; one row per time stamp once every mapped PV has a value, t in
// seconds from the first row. Lines of other PVs are not parsed. Throws
// RecordingError ("FILE:LINE: PV 'NAME': what").
Recording read_camonitor(const std::filesystem::path& file, const RecordingOptions& options);

}  // namespace truecut::analysis
