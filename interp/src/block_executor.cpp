#include "block_executor.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>

#include "arc_geometry.hpp"
#include "system_parameters.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/interp/path_geometry.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

namespace {

constexpr char kAxisLetters[6] = {'x', 'y', 'z', 'a', 'b', 'c'};
constexpr int kMotion = static_cast<int>(GGroup::kMotion);

int group(GGroup g) {
  return static_cast<int>(g);
}
int group(MGroup g) {
  return static_cast<int>(g);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string trim_left(std::string_view s) {
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t'))
    ++i;
  return std::string(s.substr(i));
}

// Centre-offset letters for the plane coordinates (XY: I J; XZ: K I; YZ: J K).
void plane_offset_letters(Plane p, char& first, char& second, char& other) {
  switch (p) {
    case Plane::kXY:
      first = 'i', second = 'j', other = 'k';
      break;
    case Plane::kXZ:
      first = 'k', second = 'i', other = 'j';
      break;
    case Plane::kYZ:
      first = 'j', second = 'k', other = 'i';
      break;
  }
}

const char* plane_name(Plane p) {
  switch (p) {
    case Plane::kXY:
      return "XY";
    case Plane::kXZ:
      return "XZ";
    case Plane::kYZ:
      return "YZ";
  }
  return "";
}

}  // namespace

void BlockExecutor::fail(int column, const std::string& message) const {
  throw GcodeError({*line_->file, line_->line, column}, message);
}

int BlockExecutor::column_of(char letter) const {
  const auto& w = (*b_)[letter];
  return w ? w->column : 0;
}

void BlockExecutor::restore_setup() {
  int index = static_cast<int>(params_.get(kCoordSystemIndex));
  if (index < 1 || index > 9) index = 1;
  const int base = coord_system_base(index);
  for (int i = 0; i < 6; ++i)
    s_.g5x_mm[i] = s_.from_param(i, params_.get(base + i));
  s_.rotation_deg = params_.get(base + kCoordSystemRotation);
  s_.coord_index = index;
  // LinuxCNC restores the G92 offsets for any non-zero #5210, not only 1.
  if (params_.get(kG92Enabled) != 0.0)
    for (int i = 0; i < 6; ++i)
      s_.g92_mm[i] = s_.from_param(i, params_.get(kG92Offsets + i));
}

void BlockExecutor::start_program() {
  out_.emit(UseLengthUnits{s_.units});
  out_.emit(SetG5xOffset{s_.coord_index, s_.to_program(s_.g5x_mm)});
  out_.emit(SetG92Offset{s_.to_program(s_.g92_mm)});
  out_.emit(SetXYRotation{s_.rotation_deg});
  out_.emit(SetFeedReference{});
  out_.emit(OnReset{});
}

bool BlockExecutor::execute(const Block& block, const LexedLine& line) {
  b_ = &block;
  line_ = &line;
  codes_ = check_codes(block, line);
  s_.line = line.line;
  axes_used_ = false;
  check_comp_codes();
  if (block.has_polar()) check_polar(s_.plane);
  comments();
  for (const auto& k : block.sinumerik) {
    if (k.word == SinumerikWord::kTraori || k.word == SinumerikWord::kTrafoof) {
      s_.tcp = k.word == SinumerikWord::kTraori;
      out_.emit(SetTcp{s_.tcp});
    }
  }
  feed_and_speed();
  tool_select();
  io_codes();
  tool_change();
  modal_state_codes();
  spindle_and_coolant();
  override_codes();
  if (codes_.g[group(GGroup::kNonModal)] == 40) {
    if (!block.has('p')) fail(codes_.g_column[0], "G4 (dwell) needs P (seconds)");
    if (block.value('p') < 0) fail(column_of('p'), "dwell time P must not be negative");
    out_.emit(Dwell{block.value('p')});
  }
  modal_settings();
  non_modal();
  motion();
  const int change = codes_.m[group(MGroup::kToolChange)];
  if (change == 60 || change == 610) {
    // LinuxCNC re-reads the position from the machine after a tool change:
    // the last commanded numbers, now under the new offsets.
    s_.position_mm = s_.machine_position(last_program_position_);
  }
  const int stop = codes_.m[group(MGroup::kStop)];
  if (stop == 0 || stop == 10 || stop == 20 || stop == 300) comp_flush();
  if (stop == 0) out_.emit(ProgramStop{false});
  if (stop == 10) out_.emit(ProgramStop{true});
  if (stop == 20 || stop == 300) {
    end_program(stop == 300);
    return true;
  }
  return false;
}

void BlockExecutor::comments() {
  for (const auto& c : b_->comments)
    if (auto op = operation_from_comment(c.text)) s_.operation = *op;
  // Like LinuxCNC, only the last parenthesized comment of a line becomes a
  // call; ';' comments are dropped.
  const CommentText* last = nullptr;
  for (const auto& c : b_->comments)
    if (!c.semicolon) last = &c;
  if (!last) return;
  const std::string& text = last->text;
  const std::string low = lower(trim_left(text));
  if (low.rfind("msg,", 0) == 0) {
    out_.emit(Message{text.substr(text.find(',') + 1)});
    return;
  }
  if (low.rfind("debug,", 0) == 0) {
    if (params_.get(kDebugSwitch) == 0.0) return;  // #5599 = 0 silences (DEBUG,...)
    out_.emit(Message{substitute_parameters(text.substr(text.find(',') + 1))});
    return;
  }
  // The log file: canonical calls, as rs274 makes them (the text after the
  // comma as written; LOG replaces parameters like DEBUG).
  const std::string after_comma = text.substr(text.find(',') + 1);
  if (low.rfind("logopen,", 0) == 0) return out_.emit(LogFile{LogFile::kOpen, after_comma});
  if (low.rfind("logappend,", 0) == 0) return out_.emit(LogFile{LogFile::kAppend, after_comma});
  if (low == "logclose") return out_.emit(LogFile{LogFile::kClose, {}});
  if (low.rfind("log,", 0) == 0)
    return out_.emit(LogFile{LogFile::kLine, substitute_parameters(after_comma)});
  // rs274 prints these itself (not as canonical calls); they move nothing.
  // (PROBEOPEN file) and (PROBECLOSE) stay comments, as rs274 prints them:
  // truecut writes no probe file.
  static const char* kSilent[] = {"print,", "py,"};
  for (const char* p : kSilent)
    if (low.rfind(p, 0) == 0) return;
  out_.emit(Comment{trim_left(text)});
}

std::string BlockExecutor::substitute_parameters(const std::string& text) const {
  // (debug, ...) shows parameter values: #12 and #<name> become numbers.
  std::string out;
  for (size_t i = 0; i < text.size();) {
    if (text[i] != '#') {
      out.push_back(text[i++]);
      continue;
    }
    std::optional<double> v;
    size_t end = i + 1;
    if (end < text.size() && text[end] == '<') {
      const size_t close = text.find('>', end);
      if (close != std::string::npos) {
        std::string name;
        for (size_t k = end + 1; k < close; ++k)
          if (text[k] != ' ' && text[k] != '\t')
            name.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(text[k]))));
        v = params_.named(name);
        end = close + 1;
      }
    } else {
      int index = 0;
      bool digits = false;
      while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end])) &&
             index < 100000) {
        index = index * 10 + (text[end++] - '0');
        digits = true;
      }
      if (digits && Parameters::valid_index(index)) v = params_.get(index);
    }
    if (!v) {
      out.push_back(text[i++]);
      continue;
    }
    char buf[64];
    std::snprintf(buf, sizeof buf, "%f", *v);
    out += buf;
    i = end;
  }
  return out;
}

void BlockExecutor::feed_and_speed() {
  const int spindle_mode = codes_.g[group(GGroup::kSpindleMode)];
  if (spindle_mode == 970) {
    s_.css = false;
    s_.css_max_rpm = 0;
    out_.emit(SetSpindleMode{0});
  } else if (spindle_mode == 960) {
    if (!b_->has('s'))
      fail(codes_.g_column[group(GGroup::kSpindleMode)],
           "G96 (constant surface speed) needs S (the surface speed)");
    // rs274 takes |D| and, without D, no limit (1e30).
    s_.css = true;
    s_.css_max_rpm = b_->has('d') ? std::abs(b_->value('d')) : kNoCssLimit;
    if (!std::isfinite(s_.css_max_rpm))
      fail(column_of('d'), "G96 D: the speed limit is not a finite number");
    out_.emit(SetSpindleMode{s_.css_max_rpm, true});
  }
  const int feed_mode = codes_.g[group(GGroup::kFeedMode)];
  if (feed_mode == 930) {
    out_.emit(Comment{"interpreter: feed mode set to inverse time"});
    s_.feed_mode = FeedMode::kInverseTime;
    out_.emit(SetFeedMode{s_.feed_mode});
    s_.feed = 0;
  } else if (feed_mode == 940) {
    out_.emit(Comment{"interpreter: feed mode set to units per minute"});
    s_.feed_mode = FeedMode::kUnitsPerMinute;
    out_.emit(SetFeedMode{s_.feed_mode});
    s_.feed = 0;
    out_.emit(SetFeedRate{0});
  } else if (feed_mode == 950) {
    out_.emit(Comment{"interpreter: feed mode set to units per revolution"});
    s_.feed_mode = FeedMode::kUnitsPerRevolution;
    out_.emit(SetFeedMode{s_.feed_mode});
    s_.feed = 0;
    out_.emit(SetFeedRate{0});
  }
  if (b_->has('f')) {
    if (b_->value('f') < 0) fail(column_of('f'), "negative feed rate F");
    if (s_.feed_mode != FeedMode::kInverseTime) {
      s_.feed = b_->value('f');
      out_.emit(SetFeedRate{s_.feed});
    }
  }
  if (b_->has('s')) {
    if (b_->value('s') < 0) fail(column_of('s'), "negative spindle speed S");
    s_.speed = b_->value('s');
    out_.emit(SetSpindleSpeed{s_.speed});
  }
}

void BlockExecutor::tool_select() {
  if (b_->has('t')) {
    const double t = b_->value('t');
    if (t < 0 || t != std::floor(t))
      fail(column_of('t'), "tool number T must be a whole number >= 0");
    if (t > kLargestWholeWord)
      fail(column_of('t'), "tool T" + rt::format_shortest(t) + " is not in the tool table");
    const int tool = static_cast<int>(t);
    if (tool != 0 && !tools_.find(tool))
      fail(column_of('t'), "tool T" + std::to_string(tool) + " is not in the tool table");
    s_.selected_tool = tool;
    out_.emit(SelectTool{tool});
  }
}

void BlockExecutor::tool_change() {
  const int change = codes_.m[group(MGroup::kToolChange)];
  if (change == 60) {
    out_.emit(StartChange{});
    out_.emit(StopSpindle{});
    s_.spindle = 0;
    const auto slot = tools_.slot_of(s_.selected_tool);
    s_.tool = s_.selected_tool;
    s_.spindle_slot = slot.value_or(0);
    out_.emit(ChangeTool{s_.tool, slot.value_or(0)});
    loaded_tool_parameters();
  } else if (change == 610) {
    if (!b_->has('q'))
      fail(codes_.m_column[group(MGroup::kToolChange)], "M61 needs Q (tool number)");
    const double q = b_->value('q');
    if (q < 0 || q != std::floor(q)) fail(column_of('q'), "M61 Q must be a whole number >= 0");
    if (q > kLargestWholeWord)
      fail(column_of('q'), "tool " + rt::format_shortest(q) + " is not in the tool table");
    const int tool = static_cast<int>(q);
    if (tool != 0 && !tools_.find(tool))
      fail(column_of('q'), "tool " + std::to_string(tool) + " is not in the tool table");
    s_.tool = s_.selected_tool = tool;
    s_.spindle_slot = tools_.slot_of(tool).value_or(0);
    out_.emit(ChangeToolNumber{tool, s_.spindle_slot});
  }
}

void BlockExecutor::spindle_and_coolant() {
  switch (codes_.m[group(MGroup::kSpindle)]) {
    case 30:
      s_.spindle = 1;
      out_.emit(StartSpindle{true});
      break;
    case 40:
      s_.spindle = -1;
      out_.emit(StartSpindle{false});
      break;
    case 50:
      s_.spindle = 0;
      out_.emit(StopSpindle{});
      break;
    case 190:
      spindle_orient();
      break;
    default:
      break;
  }
  switch (codes_.m[group(MGroup::kCoolant)]) {
    case 70:
      s_.mist = true;
      out_.emit(Coolant{Coolant::kMist, true});
      break;
    case 80:
      s_.flood = true;
      out_.emit(Coolant{Coolant::kFlood, true});
      break;
    case 90:
      s_.mist = s_.flood = false;
      out_.emit(Coolant{Coolant::kMist, false});
      out_.emit(Coolant{Coolant::kFlood, false});
      break;
    default:
      break;
  }
}

void BlockExecutor::modal_settings() {
  if (const int p = codes_.g[group(GGroup::kPlane)]; p >= 0)
    check_comp_plane_change(p == 170 ? Plane::kXY : p == 180 ? Plane::kXZ : Plane::kYZ);
  switch (codes_.g[group(GGroup::kPlane)]) {
    case 170:
      s_.plane = Plane::kXY;
      out_.emit(SelectPlane{s_.plane});
      break;
    case 180:
      s_.plane = Plane::kXZ;
      out_.emit(SelectPlane{s_.plane});
      break;
    case 190:
      s_.plane = Plane::kYZ;
      out_.emit(SelectPlane{s_.plane});
      break;
    default:
      break;
  }
  switch (codes_.g[group(GGroup::kUnits)]) {
    case 200:
      set_units(LengthUnits::kInch);
      break;
    case 210:
      set_units(LengthUnits::kMm);
      break;
    default:
      break;
  }
  if (const int comp = codes_.g[group(GGroup::kCutterComp)]; comp == 400)
    comp_off();
  else if (comp >= 0)
    comp_on(comp);
  tool_length_offset();
  const int cs = codes_.g[group(GGroup::kCoordSystem)];
  if (cs >= 0) {
    static const int kCodes[] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
    for (int i = 0; i < 9; ++i) {
      if (kCodes[i] != cs) continue;
      if (i + 1 == s_.coord_index)
        out_.emit(Comment{"interpreter: continuing to use same coordinate system"});
      else
        select_coord_system(i + 1);
    }
  }
  switch (codes_.g[group(GGroup::kPathControl)]) {
    case 610:
      s_.path = PathMode::kExactPath;
      out_.emit(SetMotionControlMode{s_.path, 0});
      break;
    case 611:
      s_.path = PathMode::kExactStop;
      out_.emit(SetMotionControlMode{s_.path, 0});
      break;
    case 640: {
      const double p = b_->has('p') ? b_->value('p') : 0.0;
      const double q = b_->has('q') ? b_->value('q') : p;
      if (p < 0) fail(column_of('p'), "G64 P (blend tolerance) must not be negative");
      if (q < 0) fail(column_of('q'), "G64 Q (naive CAM tolerance) must not be negative");
      s_.path = PathMode::kContinuous;
      s_.blend_tolerance = p;
      s_.naive_tolerance = q;
      out_.emit(SetMotionControlMode{s_.path, p});
      out_.emit(SetNaivecamTolerance{q});
      break;
    }
    default:
      break;
  }
  const int dist = codes_.g[group(GGroup::kDistance)];
  if (dist == 900 && s_.incremental) {
    s_.incremental = false;
    out_.emit(Comment{"interpreter: distance mode changed to absolute"});
  } else if (dist == 910 && !s_.incremental) {
    s_.incremental = true;
    out_.emit(Comment{"interpreter: distance mode changed to incremental"});
  }
  const int arc_dist = codes_.g[group(GGroup::kArcDistance)];
  if (arc_dist == 901 && !s_.arc_absolute) {
    s_.arc_absolute = true;
    out_.emit(Comment{"interpreter: IJK distance mode changed to absolute"});
  } else if (arc_dist == 911 && s_.arc_absolute) {
    s_.arc_absolute = false;
    out_.emit(Comment{"interpreter: IJK distance mode changed to incremental"});
  }
  switch (codes_.g[group(GGroup::kRetract)]) {
    case 980:
      s_.retract_old_z = true;
      out_.emit(Comment{"interpreter: retract mode set to old_z"});
      break;
    case 990:
      s_.retract_old_z = false;
      out_.emit(Comment{"interpreter: retract mode set to r_plane"});
      break;
    default:
      break;
  }
}

void BlockExecutor::set_units(LengthUnits units) {
  if (units != s_.units && s_.comp.side != 0)
    fail(codes_.g_column[group(GGroup::kUnits)],
         "changing units (G20/G21) with cutter radius compensation on is not supported (G40 "
         "first)");
  s_.units = units;
  out_.emit(UseLengthUnits{units});
}

void BlockExecutor::emit_offsets() {
  out_.emit(SetG5xOffset{s_.coord_index, s_.to_program(s_.g5x_mm)});
  out_.emit(SetG92Offset{s_.to_program(s_.g92_mm)});
  out_.emit(SetXYRotation{s_.rotation_deg});
}

void BlockExecutor::select_coord_system(int index) {
  const int base = coord_system_base(index);
  for (int i = 0; i < 6; ++i)
    s_.g5x_mm[i] = s_.from_param(i, params_.get(base + i));
  s_.rotation_deg = params_.get(base + kCoordSystemRotation);
  s_.coord_index = index;
  params_.set(kCoordSystemIndex, index);
  emit_offsets();
}

void BlockExecutor::tool_length_offset() {
  const int code = codes_.g[group(GGroup::kToolLength)];
  if (code == 490) {
    s_.tool_length_code = 490;
    s_.tool_offset_mm = Axes6{};
    out_.emit(UseToolLengthOffset{Axes6{}});
    return;
  }
  if (code == 431 || code == 432) return dynamic_tool_length(code);
  if (code != 430) {
    if (b_->has('h')) fail(column_of('h'), "H word without G43 to use it");
    return;
  }
  int tool = s_.tool;
  if (b_->has('h')) {
    const double h = b_->value('h');
    if (h < 0 || h != std::floor(h)) fail(column_of('h'), "H must be a whole number >= 0");
    if (h > kLargestWholeWord)
      fail(column_of('h'), "H" + rt::format_shortest(h) + ": no such tool in the tool table");
    if (h != 0) tool = static_cast<int>(h);  // H0: the tool in the spindle, as rs274
  }
  Axes6 offset;
  if (tool != 0) {
    const ToolEntry* e = tools_.find(tool);
    if (!e)
      fail(b_->has('h') ? column_of('h') : codes_.g_column[group(GGroup::kToolLength)],
           "tool " + std::to_string(tool) + " for G43 is not in the tool table");
    offset = e->offset_mm;
  }
  s_.tool_offset_mm = offset;
  s_.tool_length_code = 430;
  out_.emit(UseToolLengthOffset{s_.to_program(offset)});
}

void BlockExecutor::dynamic_tool_length(int code) {
  const int col = codes_.g_column[group(GGroup::kToolLength)];
  bool axis_words = false;
  for (char l : kAxisLetters)
    axis_words = axis_words || b_->has(l);
  Axes6 offset = s_.tool_offset_mm;
  if (code == 431) {
    // G43.1: the given axes' offsets are the words (in G91 too); the others
    // stay as they are.
    if (b_->has('h')) fail(column_of('h'), "H word with G43.1 (the offsets are the axis words)");
    for (int i = 0; i < 6; ++i)
      if (b_->has(kAxisLetters[i])) offset[i] = s_.to_machine(i, b_->value(kAxisLetters[i]));
    // rs274: without a motion code on the line the words are G43.1's only;
    // with one, the move takes them too.
    if (codes_.g[kMotion] < 0) axes_used_ = true;
  } else {
    // G43.2 H: tool H's offsets are added to those in force.
    if (axis_words)
      fail(col, "G43.2 with axis words: truecut and rs274 take only H (a tool to add)");
    if (!b_->has('h')) fail(col, "G43.2 needs H (the tool whose offsets are added)");
    const double h = b_->value('h');
    if (h < 0 || h != std::floor(h)) fail(column_of('h'), "H must be a whole number >= 0");
    if (h > kLargestWholeWord)
      fail(column_of('h'), "H" + rt::format_shortest(h) + ": no such tool in the tool table");
    const int tool = h == 0 ? s_.tool : static_cast<int>(h);  // H0: the tool in the spindle
    if (tool != 0) {
      const ToolEntry* e = tools_.find(tool);
      if (!e)
        fail(column_of('h'),
             "tool " + std::to_string(tool) + " for G43.2 is not in the tool table");
      for (int i = 0; i < 6; ++i)
        offset[i] += e->offset_mm[i];
    }
  }
  for (int i = 0; i < 6; ++i)
    if (!std::isfinite(offset[i])) fail(col, "the tool length offset is not a finite number");
  s_.tool_offset_mm = offset;
  // rs274 saves and restores G43.1/G43.2 as G43 (M70-M73).
  s_.tool_length_code = 430;
  out_.emit(UseToolLengthOffset{s_.to_program(offset)});
}

void BlockExecutor::non_modal() {
  const int code = codes_.g[group(GGroup::kNonModal)];
  if (code == 100 || code == 520 || code == 920) {
    const int motion_code = codes_.g[kMotion];
    if (motion_code >= 0 && motion_code != 800)
      fail(codes_.g_column[kMotion], std::string(code == 100   ? "G10"
                                                 : code == 520 ? "G52"
                                                               : "G92") +
                                         " and a motion code on one line: both use the axis words");
  }
  if (code == 100) coord_system_data();
  if (code == 280 || code == 300 || code == 281 || code == 301) go_home(code);
  if ((code >= 920 && code <= 923) || code == 520) g92_offsets(code);
}

void BlockExecutor::coord_system_data() {
  const int col = codes_.g_column[0];
  if (!b_->has('l')) fail(col, "G10 needs L (L1, L10, L11, L2 or L20)");
  const double l = b_->value('l');
  if (l == 1 || l == 10 || l == 11) return tool_table_edit(static_cast<int>(l));
  if (l == 0) fail(column_of('l'), "G10 L0 (reload the tool table) is not supported");
  if (l != 2 && l != 20) fail(column_of('l'), "G10 supports L1, L10, L11, L2 and L20");
  if (!b_->has('p')) fail(col, "G10 L2/L20 needs P (coordinate system 0..9)");
  const double pv = b_->value('p');
  if (pv < 0 || pv > 9 || pv != std::floor(pv))
    fail(column_of('p'), "G10 P must be a coordinate system 0..9 (0 = active)");
  if (l == 20 && b_->has('r'))
    fail(column_of('r'),
         "G10 L20 does not take R: a coordinate system's rotation is set with G10 L2 R");
  if (b_->has('r') && !std::isfinite(b_->value('r')))
    fail(column_of('r'), "G10 L2 R: the rotation is not a finite number");
  const int index = pv == 0 ? s_.coord_index : static_cast<int>(pv);
  const int base = coord_system_base(index);
  if (l == 2) {
    for (int i = 0; i < 6; ++i)
      if (b_->has(kAxisLetters[i]))
        params_.set(base + i, s_.to_param(i, s_.to_machine(i, b_->value(kAxisLetters[i]))));
    if (b_->has('r')) params_.set(base + kCoordSystemRotation, b_->value('r'));
  } else {
    set_origin_at_tool(base);
  }
  axes_used_ = true;
  if (index == s_.coord_index) {
    const Axes6 old_g5x = s_.g5x_mm, program = s_.program_position();
    const double old_rotation = s_.rotation_deg;
    for (int i = 0; i < 6; ++i)
      s_.g5x_mm[i] = s_.from_param(i, params_.get(base + i));
    s_.rotation_deg = params_.get(base + kCoordSystemRotation);
    if (s_.rotation_deg != old_rotation && (s_.g92_mm.x != 0 || s_.g92_mm.y != 0)) {
      // rs274 turns the program position into the new frame without the
      // G92/G52 offset: p' = R(-new) (R(old) p + old origin - new origin).
      // The machine has not moved, but rs274 continues from p' (its next
      // incremental moves and arc starts), so truecut does too.
      double x = s_.to_machine(0, program.x), y = s_.to_machine(1, program.y);
      rotate_xy_deg(x, y, old_rotation);
      x += old_g5x.x - s_.g5x_mm.x;
      y += old_g5x.y - s_.g5x_mm.y;
      rotate_xy_deg(x, y, -s_.rotation_deg);
      Axes6 p = s_.program_position();
      p.x = s_.to_program(0, x);
      p.y = s_.to_program(1, y);
      const Axes6 m = s_.machine_position(p);
      s_.position_mm.x = m.x;
      s_.position_mm.y = m.y;
    }
    out_.emit(SetG5xOffset{s_.coord_index, s_.to_program(s_.g5x_mm)});
    out_.emit(SetXYRotation{s_.rotation_deg});
  } else {
    Comment note{"interpreter: setting coordinate system origin"};
    note.sets_system = index;
    for (int i = 0; i < 6; ++i)
      note.system_origin[i] = s_.to_program(i, s_.from_param(i, params_.get(base + i)));
    note.system_rotation_deg = params_.get(base + kCoordSystemRotation);
    out_.emit_now(std::move(note));
  }
}

// G10 L20: the origin of the system at `base` that puts the tool at the
// words with the G92/G52 offset still applied on top, as rs274 computes it.
// Under a rotation (the target system's) X and Y are set together: the
// tool's position in the target system (its old origin, its rotation),
// with the given words replaced, fixes both.
void BlockExecutor::set_origin_at_tool(int base) {
  const double rotation = params_.get(base + kCoordSystemRotation);
  if (rotation == 0 && s_.rotation_deg == 0) {
    const Axes6 prog = s_.program_position();
    const Axes6 g5x = s_.to_program(s_.g5x_mm);
    for (int i = 0; i < 6; ++i)
      if (b_->has(kAxisLetters[i]))
        params_.set(base + i, s_.to_param(i, s_.to_machine(i, prog[i] + g5x[i] -
                                                                  b_->value(kAxisLetters[i]))));
    return;
  }
  const Axes6& m = s_.position_mm;
  for (int i = 2; i < 6; ++i)
    if (b_->has(kAxisLetters[i]))
      params_.set(base + i, s_.to_param(i, m[i] - s_.g92_mm[i] - s_.tool_offset_mm[i] -
                                               s_.to_machine(i, b_->value(kAxisLetters[i]))));
  if (!b_->has('x') && !b_->has('y')) return;
  double x = m.x - s_.tool_offset_mm.x - s_.from_param(0, params_.get(base));
  double y = m.y - s_.tool_offset_mm.y - s_.from_param(1, params_.get(base + 1));
  rotate_xy_deg(x, y, -rotation);
  x -= s_.g92_mm.x;
  y -= s_.g92_mm.y;
  if (b_->has('x')) x = s_.to_machine(0, b_->value('x'));
  if (b_->has('y')) y = s_.to_machine(1, b_->value('y'));
  x += s_.g92_mm.x;
  y += s_.g92_mm.y;
  rotate_xy_deg(x, y, rotation);
  params_.set(base, s_.to_param(0, m.x - s_.tool_offset_mm.x - x));
  params_.set(base + 1, s_.to_param(1, m.y - s_.tool_offset_mm.y - y));
}

void BlockExecutor::g92_offsets(int code) {
  if (code == 520) {
    // G52 (LinuxCNC 2.9): the given axes' offsets are the words, in G90 and
    // G91 alike; the others keep the offsets in force (0 after G92.1/G92.2).
    bool any = false;
    for (int i = 0; i < 6; ++i) {
      const char letter = kAxisLetters[i];
      if (!b_->has(letter)) continue;
      any = true;
      s_.g92_mm[i] = s_.to_machine(i, b_->value(letter));
    }
    if (!any) fail(codes_.g_column[0], "G52 needs at least one axis word");
    axes_used_ = true;
    for (int i = 0; i < 6; ++i)
      params_.set(kG92Offsets + i, s_.to_param(i, s_.g92_mm[i]));
    params_.set(kG92Enabled, 1);
  } else if (code == 920) {
    bool any = false;
    const Axes6 prog = s_.program_position();
    for (int i = 0; i < 6; ++i) {
      const char letter = kAxisLetters[i];
      if (!b_->has(letter)) continue;
      any = true;
      const double offset = prog[i] + s_.to_program(i, s_.g92_mm[i]) - b_->value(letter);
      s_.g92_mm[i] = s_.to_machine(i, offset);
    }
    if (!any) fail(codes_.g_column[0], "G92 needs at least one axis word");
    axes_used_ = true;
    for (int i = 0; i < 6; ++i)
      params_.set(kG92Offsets + i, s_.to_param(i, s_.g92_mm[i]));
    params_.set(kG92Enabled, 1);
  } else if (code == 921 || code == 922) {
    s_.g92_mm = Axes6{};
    if (code == 921)
      for (int i = 0; i < 6; ++i)
        params_.set(kG92Offsets + i, 0);
    params_.set(kG92Enabled, 0);
  } else {  // G92.3
    for (int i = 0; i < 6; ++i)
      s_.g92_mm[i] = s_.from_param(i, params_.get(kG92Offsets + i));
    params_.set(kG92Enabled, 1);
  }
  out_.emit(SetG92Offset{s_.to_program(s_.g92_mm)});
}

void BlockExecutor::go_home(int code) {
  const int base = (code == 280 || code == 281) ? kG28Home : kG30Home;
  if (code == 281 || code == 301) {  // store the current machine position
    for (int i = 0; i < 6; ++i)
      params_.set(base + i, s_.to_param(i, s_.position_mm[i]));
    return;
  }
  if (codes_.g[kMotion] >= 0)
    fail(codes_.g_column[kMotion], "G28/G30 and a motion code on one line");
  bool any = false;
  for (char l : kAxisLetters)
    any = any || b_->has(l);
  // Through the programmed point (where the tool is, without axis words),
  // then home for the programmed axes (all without axis words).
  const Axes6 via = target_position(false);
  out_.emit(StraightTraverse{s_.program_position(via)});
  last_program_position_ = s_.program_position(via);
  s_.position_mm = via;
  Axes6 home = via;
  for (int i = 0; i < 6; ++i)
    if (!any || b_->has(kAxisLetters[i])) home[i] = s_.from_param(i, params_.get(base + i));
  if (s_.rotation_deg != 0) {
    // rs274 takes the home's program coordinates for the programmed axes
    // (in the rotated frame) and keeps the others'.
    Axes6 all;
    for (int i = 0; i < 6; ++i)
      all[i] = s_.from_param(i, params_.get(base + i));
    const Axes6 home_program = s_.program_position(all);
    Axes6 p = s_.program_position(via);
    for (int i = 0; i < 6; ++i)
      if (!any || b_->has(kAxisLetters[i])) p[i] = home_program[i];
    home = s_.machine_position(p);
  }
  out_.emit(StraightTraverse{s_.program_position(home)});
  last_program_position_ = s_.program_position(home);
  s_.position_mm = home;
  axes_used_ = true;
}

Axes6 BlockExecutor::move_base() const {
  Axes6 base = s_.position_mm;
  // Under cutter compensation, LinuxCNC measures from the programmed point,
  // not from where the compensated tool is.
  if (s_.comp.active() && !s_.comp.first_move) {
    const Axes6 programmed = s_.machine_position(s_.comp.programmed);
    for (int i = 0; i < 3; ++i)
      base[i] = programmed[i];
  }
  return base;
}

Axes6 BlockExecutor::target_position(bool machine_coords) const {
  const Axes6 base = move_base();
  if (s_.rotation_deg != 0 && !machine_coords) {
    // In the rotated frame: program coordinates, then back to the machine.
    Axes6 p = s_.program_position(base);
    for (int i = 0; i < 6; ++i) {
      const char letter = kAxisLetters[i];
      if (b_->has(letter)) p[i] = (s_.incremental ? p[i] : 0) + b_->value(letter);
    }
    Axes6 t = s_.machine_position(p);
    for (int i = 2; i < 6; ++i)
      if (!b_->has(kAxisLetters[i])) t[i] = base[i];
    return t;
  }
  Axes6 t = base;
  for (int i = 0; i < 6; ++i) {
    const char letter = kAxisLetters[i];
    if (!b_->has(letter)) continue;
    const double v = s_.to_machine(i, b_->value(letter));
    if (machine_coords)
      t[i] = v;
    else if (s_.incremental)
      t[i] = base[i] + v;
    else
      t[i] = v + s_.g5x_mm[i] + s_.g92_mm[i] + s_.tool_offset_mm[i];
  }
  return t;
}

void BlockExecutor::check_polar(Plane plane_before) const {
  const int col = b_->polar_column();
  // LinuxCNC checks the plane in force before the line.
  if (plane_before != Plane::kXY)
    fail(col, std::string("polar coordinates (@ ^) only in the XY plane: the plane before this "
                          "line is ") +
                  plane_name(plane_before) + " (program G17 on an earlier line)");
  for (char l : {'x', 'y'})
    if (b_->has(l))
      fail(column_of(l), std::string("polar coordinates (@ ^) and the ") +
                             static_cast<char>(std::toupper(l)) +
                             " word on one line: use one form");
  const int nm = codes_.g[group(GGroup::kNonModal)];
  if (nm == 100 || nm == 280 || nm == 300 || nm == 920 || nm == 520)
    fail(col, "polar coordinates (@ ^) are for motion only, not for G10, G28, G30, G52 or G92");
  if (b_->has_g(530)) fail(col, "polar coordinates (@ ^) with G53");
}

void BlockExecutor::polar_point(double& x, double& y) const {
  const int col = b_->polar_column();
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  double radius = std::hypot(x, y), angle = std::atan2(y, x);
  // rs274 keeps program numbers; truecut's come back from machine millimetres.
  const bool at_origin = std::abs(x) < 1e-12 && std::abs(y) < 1e-12;
  if (!s_.incremental) {
    if (b_->polar_radius && !b_->polar_angle && at_origin)
      fail(col, "@ without ^ at the origin: the angle is undefined (give ^)");
    if (b_->polar_radius) radius = b_->polar_radius->value;
    if (b_->polar_angle) angle = b_->polar_angle->value * kDeg;
  } else {
    if (at_origin)
      fail(col, "incremental polar coordinates (G91 @ ^) at the origin: the angle is undefined");
    if (b_->polar_radius) radius += b_->polar_radius->value;
    if (b_->polar_angle) angle += b_->polar_angle->value * kDeg;
  }
  x = radius * std::cos(angle);
  y = radius * std::sin(angle);
  if (!std::isfinite(x) || !std::isfinite(y))
    fail(col, "the polar point overflows: its X or Y is not a finite number");
}

void BlockExecutor::check_feed(int column) const {
  if (s_.feed_mode == FeedMode::kInverseTime) {
    if (!b_->has('f')) fail(column, "inverse-time feed (G93) needs an F word on every feed move");
    if (b_->value('f') <= 0) fail(column_of('f'), "inverse-time F must be greater than zero");
  } else if (s_.feed <= 0) {
    fail(column, "feed move with a zero feed rate: program F before or on this line");
  } else if (s_.feed_mode == FeedMode::kUnitsPerRevolution && s_.speed == 0) {
    fail(column, "feed per revolution (G95) with spindle speed S0: the move would not advance");
  }
}

void BlockExecutor::check_unused_words(int motion_code) const {
  const bool arc = motion_code == 20 || motion_code == 30;
  const bool cycle = is_canned_cycle(motion_code);
  const bool dwell_cycle = motion_code == 740 || motion_code == 820 || motion_code == 840 ||
                           motion_code == 860 || motion_code == 880 || motion_code == 890;
  const bool peck_cycle = motion_code == 730 || motion_code == 830;
  const int nm = codes_.g[0];
  const int io = codes_.m[group(MGroup::kUser)];
  const int spindle = codes_.m[group(MGroup::kSpindle)];
  const int override_code = codes_.m[group(MGroup::kOverride)];
  const bool orient = spindle == 190;
  const bool tool_edit = nm == 100 && b_->has('l') &&
                         (b_->value('l') == 1 || b_->value('l') == 10 || b_->value('l') == 11);
  const bool g5 = motion_code == 50, g5_1 = motion_code == 51, nurbs = motion_code == 52;
  for (char l : {'i', 'j', 'k', 'r'})
    if (b_->has(l) && !arc && !(l == 'r' && (nm == 100 || cycle || orient)) &&
        !((g5 || g5_1) && (l == 'i' || l == 'j')) && !(tool_edit && (l == 'i' || l == 'j')) &&
        !(l != 'r' && motion_code == 870) &&
        !(l == 'k' && (motion_code == 330 || motion_code == 331))) {
      if (cycle)
        fail(column_of(l), std::string(1, static_cast<char>(std::toupper(l))) +
                               " word in a canned cycle (only G87 uses I, J, K)");
      fail(column_of(l), std::string(1, static_cast<char>(std::toupper(l))) +
                             " word with no G2 or G3 to use it (G5, G5.1 take I J)");
    }
  if (b_->has('p') && !arc && !dwell_cycle && nm != 40 && nm != 100 && !g5 && !nurbs &&
      codes_.g[group(GGroup::kPathControl)] != 640 && !orient && override_code < 500 &&
      !(io >= 620 && io <= 660))
    fail(
        column_of('p'),
        "P word with no code that uses it (G4, G10, G64, G2/G3, G5, G5.2, G74/G82/G84/G86/G88/G89, "
        "M19, "
        "M50-M53, M62-M66)");
  if (b_->has('q') && !peck_cycle && !g5 && codes_.g[group(GGroup::kPathControl)] != 640 &&
      codes_.m[group(MGroup::kToolChange)] != 610 && !orient && !(io >= 660 && io <= 680) &&
      !tool_edit)
    fail(column_of('q'),
         "Q word with no code that uses it (G10 L1, G64, G5, M61, G73/G83, M19, M66-M68)");
  if (b_->has('e') && !(io >= 660 && io <= 680))
    fail(column_of('e'), "E word with no M66, M67 or M68 to use it");
  const int comp = codes_.g[group(GGroup::kCutterComp)];
  if (b_->has('l') && nm != 100 && !cycle && !nurbs && comp != 411 && comp != 421 && io != 660)
    fail(column_of('l'), "L word with no G10, canned cycle, G5.2 or M66 to use it");
  if (b_->has('d') && comp != 410 && comp != 411 && comp != 420 && comp != 421 &&
      codes_.g[group(GGroup::kSpindleMode)] != 960)
    fail(column_of('d'), "D word with no G41, G41.1, G42, G42.1 or G96 to use it");
}

void BlockExecutor::motion() {
  const int explicit_code = codes_.g[kMotion];
  const bool g53 = b_->has_g(530);
  bool axis_words = false;
  int first_axis_column = 0;
  for (char l : kAxisLetters)
    if (b_->has(l)) {
      axis_words = true;
      if (!first_axis_column) first_axis_column = column_of(l);
    }
  if (b_->has_polar()) {  // @ ^ count as axis words
    axis_words = true;
    if (!first_axis_column) first_axis_column = b_->polar_column();
  }
  // G5 and G5.1 leave the motion mode as it was (as in rs274).
  const bool one_shot_spline = explicit_code == 50 || explicit_code == 51;
  if (explicit_code >= 0 && explicit_code != 52 && explicit_code != 53)
    check_nurbs_closed(codes_.g_column[kMotion],
                       explicit_code >= 10000 ? std::string("a spline word")
                       : explicit_code % 10   ? "G" + std::to_string(explicit_code / 10) + "." +
                                                  std::to_string(explicit_code % 10)
                                            : "G" + std::to_string(explicit_code / 10));
  if (explicit_code >= 0 && !one_shot_spline) {
    const SplineMode before = s_.spline;
    s_.motion = explicit_code;
    s_.spline = explicit_code == kBsplineCode   ? SplineMode::kBspline
                : explicit_code == kCsplineCode ? SplineMode::kCspline
                                                : SplineMode::kNone;
    if (s_.spline != before) out_.emit(SetSplineMode{s_.spline});
    if (explicit_code == 800) out_.emit(Comment{"interpreter: motion mode set to none"});
    if (!is_canned_cycle(explicit_code)) {
      // Any other motion mode ends the run of cycles: the next cycle starts
      // afresh (needs R and Z again, takes a new initial level).
      s_.cycle.last_code = -1;
      s_.cycle.level_set = false;
    }
  }
  const int code = one_shot_spline                                       ? explicit_code
                   : (explicit_code >= 0 || (axis_words && !axes_used_)) ? s_.motion
                                                                         : -1;
  check_unused_words(code);
  if (explicit_code < 0 && axis_words && !axes_used_ && s_.motion == kMotionNone)
    fail(first_axis_column,
         "axis words with no motion mode (G5.3 ended the NURBS): program G0, G1, G2 or G3");
  if (g53) {
    if (code != 0 && code != 10) fail(b_->g[0].column, "G53 needs G0 or G1 on the line or active");
    if (s_.incremental) fail(b_->g[0].column, "G53 with incremental distance mode (G91)");
    if (s_.comp.active()) fail(b_->g[0].column, "cannot use G53 with cutter radius compensation");
  }
  if (code < 0 || axes_used_) return;
  if (code == 800) {
    if (axis_words)
      fail(first_axis_column,
           "axis words with no motion mode (G80 active): program G0, G1, G2 or G3");
    return;
  }
  const int motion_column = explicit_code >= 0 ? codes_.g_column[kMotion] : first_axis_column;
  if (is_canned_cycle(code)) {
    if (s_.comp.side != 0)
      fail(motion_column ? motion_column : 1,
           "cannot use canned cycles with cutter radius compensation on (G40 first)");
    // The cycle's moves carry its code (CallContext::canned_cycle), also
    // when it fails half way.
    struct Running {
      CycleState& cycle;
      ~Running() { cycle.running = 0; }
    } running{s_.cycle};
    s_.cycle.running = code;
    canned_cycle(code, motion_column ? motion_column : 1);
    return;
  }
  Axes6 target = target_position(g53);
  if (b_->has_polar()) {
    const Axes6 here = s_.program_position(move_base());
    double x = here[0], y = here[1];
    polar_point(x, y);
    Axes6 p = s_.program_position(target);
    p.x = x;
    p.y = y;
    const Axes6 m = s_.machine_position(p);
    target.x = m.x;
    target.y = m.y;
  }
  if (code >= 50 && code <= 53) {
    spline(code, target, motion_column ? motion_column : 1, axis_words);
    return;
  }
  if (code == 330 || code == 331) {
    sync_motion(code, target, motion_column ? motion_column : 1, axis_words);
    return;
  }
  if (code >= 382 && code <= 385) {
    probe(code, target, motion_column ? motion_column : 1, axis_words);
    return;
  }
  if (code == 20 || code == 30) {
    arc(code == 20, target);
    return;
  }
  // An explicit G0/G1 without axis words is a move to where the tool is.
  if (!axis_words && (code == kBsplineCode || code == kCsplineCode)) return;
  if (s_.comp.side != 0 && (code == kBsplineCode || code == kCsplineCode))
    fail(motion_column ? motion_column : 1,
         "BSPLINE/CSPLINE points with cutter radius compensation on are not supported (G40 "
         "first)");
  if (code != 0) check_feed(motion_column);
  s_.comp.arc_not_allowed = false;
  straight(code == 0, target, motion_column);
}

void BlockExecutor::straight(bool rapid, const Axes6& target, int column) {
  const Axes6 end = s_.program_position(target);
  if (rapid && s_.comp.active()) {
    comp_straight(true, target, column);
    return;
  }
  if (rapid) {
    out_.emit(StraightTraverse{end});
  } else {
    double f = 0;
    if (s_.feed_mode == FeedMode::kInverseTime) {
      // LinuxCNC turns inverse time into a rate: the move's length times F,
      // the XYZ length when XYZ move, else the rotary one; under cutter
      // compensation the programmed length (from the programmed point).
      const Axes6 start = s_.program_position(move_base());
      double linear = 0, rotary = 0;
      for (int i = 0; i < 3; ++i)
        linear += (end[i] - start[i]) * (end[i] - start[i]);
      for (int i = 3; i < 6; ++i)
        rotary += (end[i] - start[i]) * (end[i] - start[i]);
      const double length = linear > 0 ? std::sqrt(linear) : std::sqrt(rotary);
      f = b_->value('f');
      out_.emit(SetFeedRate{length * f}, f);
    }
    if (s_.comp.active()) {
      comp_straight(false, target, column);
      return;
    }
    out_.emit(StraightFeed{end}, f);
  }
  last_program_position_ = end;
  s_.position_mm = target;
}

void BlockExecutor::arc(bool clockwise, const Axes6& target) {
  const int code_col = codes_.g[kMotion] >= 0 ? codes_.g_column[kMotion] : 0;
  const path_geometry::PlaneAxes axes = path_geometry::plane_axes(s_.plane);
  const int first = axes.first, second = axes.second, axis = axes.normal;
  char off1, off2, off_other;
  plane_offset_letters(s_.plane, off1, off2, off_other);
  int col = code_col;
  for (char l : kAxisLetters)
    if (!col && b_->has(l)) col = column_of(l);
  if (b_->has(off_other))
    fail(column_of(off_other), std::string(1, static_cast<char>(std::toupper(off_other))) +
                                   " word given for an arc in the " + plane_name(s_.plane) +
                                   " plane");
  const bool r_form = b_->has('r');
  const bool c_form = b_->has(off1) || b_->has(off2);
  if (r_form && c_form) fail(column_of('r'), "arc with both R and I/J/K: use one form");
  if (!r_form && !c_form)
    fail(col, std::string("missing arc data: give R (radius) or ") +
                  static_cast<char>(std::toupper(off1)) + "/" +
                  static_cast<char>(std::toupper(off2)) + " (centre offsets)");
  if (s_.comp.arc_not_allowed)
    fail(col, "the move just after exiting cutter compensation (G40) must be straight, not an arc");
  ArcRequest req;
  req.clockwise = clockwise;
  const Axes6 start = s_.program_position(move_base());
  const Axes6 end = s_.program_position(target);
  req.start[0] = start[first];
  req.start[1] = start[second];
  req.end[0] = end[first];
  req.end[1] = end[second];
  req.radius_form = r_form;
  if (r_form) req.radius = b_->value('r');
  req.center_in[0] = b_->has(off1) ? b_->value(off1) : 0.0;
  req.center_in[1] = b_->has(off2) ? b_->value(off2) : 0.0;
  req.absolute_center = s_.arc_absolute;
  req.inch = s_.units == LengthUnits::kInch;
  if (b_->has('p')) {
    const double p = b_->value('p');
    if (p < 1 || p != std::floor(p))
      fail(column_of('p'), "arc turns P must be a whole number >= 1");
    if (p > kLargestWholeWord)
      fail(column_of('p'), "arc turns P " + rt::format_shortest(p) + " is too large");
    req.turns = static_cast<int>(p);
  }
  check_feed(col);
  ArcResult res;
  try {
    res = compute_arc(req);
  } catch (const ArcDataError& e) {
    int c = col;
    if (e.word == 'r') c = column_of('r');
    if (e.word == 'i') c = b_->has(off1) ? column_of(off1) : column_of(off2);
    fail(c ? c : col, e.what());
  }
  if (s_.comp.active()) {
    if (s_.feed_mode == FeedMode::kInverseTime) {
      const double f = b_->value('f');
      out_.emit(SetFeedRate{arc_length(req, res, end[axis] - start[axis]) * f}, f);
    }
    comp_arc(req, res, end, col);
    return;
  }
  ArcFeed a;
  a.end = end;
  a.center[first] = res.center[0];
  a.center[second] = res.center[1];
  a.plane = s_.plane;
  a.rotation = res.rotation;
  double f = 0;
  if (s_.feed_mode == FeedMode::kInverseTime) {
    f = b_->value('f');
    out_.emit(SetFeedRate{arc_length(req, res, end[axis] - start[axis]) * f}, f);
  }
  out_.emit(std::move(a), f);
  last_program_position_ = end;
  s_.position_mm = target;
}

void BlockExecutor::end_program(bool pallet_shuttle) {
  check_nurbs_closed(1, "the program end");
  const int base = coord_system_base(1);
  for (int i = 0; i < 6; ++i)
    s_.g5x_mm[i] = s_.from_param(i, params_.get(base + i));
  s_.rotation_deg = params_.get(base + kCoordSystemRotation);
  s_.coord_index = 1;
  out_.emit(SetG5xOffset{1, s_.to_program(s_.g5x_mm)});
  out_.emit(SetXYRotation{s_.rotation_deg});
  if (s_.plane != Plane::kXY) {
    s_.plane = Plane::kXY;
    out_.emit(SelectPlane{s_.plane});
  }
  s_.incremental = false;
  s_.feed_mode = FeedMode::kUnitsPerMinute;
  out_.emit(SetFeedMode{s_.feed_mode});
  s_.feed = 0;
  out_.emit(SetFeedRate{0});
  if (!s_.feed_override) {
    s_.feed_override = true;
    out_.emit(FeedOverride{true});
  }
  s_.spindle = 0;
  out_.emit(StopSpindle{});
  s_.css = false;
  s_.css_max_rpm = 0;
  out_.emit(SetSpindleMode{0});
  if (s_.mist) out_.emit(Coolant{Coolant::kMist, false});
  if (s_.flood) out_.emit(Coolant{Coolant::kFlood, false});
  s_.mist = s_.flood = false;
  s_.motion = 10;
  s_.cycle = CycleState{};
  s_.comp = CutterCompState{};
  if (s_.spline != SplineMode::kNone) {
    s_.spline = SplineMode::kNone;
    out_.emit(SetSplineMode{s_.spline});
  }
  if (s_.tcp) {
    s_.tcp = false;
    out_.emit(SetTcp{false});
  }
  if (pallet_shuttle) out_.emit(PalletShuttle{});
  out_.emit(ProgramEnd{});
  s_.operation.clear();
  out_.clear_block_number();
  out_.emit(OnReset{});
  out_.emit(OnReset{});
}

}  // namespace truecut::interp
