#include "program_runner.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "system_parameters.hpp"

namespace truecut::interp {

namespace {

constexpr size_t kMaxCallDepth = 100;

bool is_percent_line(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  return first != std::string::npos && s[first] == '%' &&
         s.find_first_not_of(" \t", first + 1) == std::string::npos;
}

bool is_blank(const std::string& s) {
  return s.find_first_not_of(" \t") == std::string::npos;
}

const char* keyword_name(OKeyword k) {
  switch (k) {
    case OKeyword::kSub:
      return "sub";
    case OKeyword::kEndsub:
      return "endsub";
    case OKeyword::kCall:
      return "call";
    case OKeyword::kReturn:
      return "return";
    case OKeyword::kIf:
      return "if";
    case OKeyword::kElseif:
      return "elseif";
    case OKeyword::kElse:
      return "else";
    case OKeyword::kEndif:
      return "endif";
    case OKeyword::kWhile:
      return "while";
    case OKeyword::kEndwhile:
      return "endwhile";
    case OKeyword::kDo:
      return "do";
    case OKeyword::kRepeat:
      return "repeat";
    case OKeyword::kEndrepeat:
      return "endrepeat";
    case OKeyword::kBreak:
      return "break";
    case OKeyword::kContinue:
      return "continue";
    case OKeyword::kFanucSub:
      return "(subprogram)";
  }
  return "";
}

// The digits of the line's N word as written (after an optional '/'), as
// rs274 prints them; "" when the line has none.
std::string block_number_of(const LexedLine& line) {
  size_t k = 0;
  if (k < line.text.size() && line.text[k] == '/') ++k;
  if (k >= line.text.size() || line.text[k] != 'n') return {};
  size_t end = ++k;
  while (end < line.text.size() && std::isdigit(static_cast<unsigned char>(line.text[end])))
    ++end;
  return line.text.substr(k, end - k);
}

std::string label_text(const std::string& label) {
  return "o" + label;
}

}  // namespace

ProgramRunner::ProgramRunner(const InterpreterOptions& options, CanonProgram& out)
    : options_(options),
      out_(out),
      emitter_(out, state_, &options.on_call),
      executor_(state_, params_, options.tools, emitter_) {
  if (options.probe) executor_.set_probe(&options_.probe);
  for (const auto& [number, value] : options.parameters.values)
    params_.set(number, value);
  // The offset parameters stay in the file's (the machine's) units.
  state_.machine_units = options.parameters.units;
  params_.set(kDebugSwitch, 1.0);  // rs274 shows (DEBUG,...) whatever the file holds
  executor_.restore_setup();
  params_.predefined = [this](std::string_view name) {
    return predefined_parameter(state_, params_, name);
  };
}

void ProgramRunner::fail(const LexedLine& line, int column, const std::string& message) const {
  throw GcodeError({*line.file, line.line, column}, message);
}

int ProgramRunner::add_file(SourceFile source) {
  File f;
  f.source = std::move(source);
  f.end = f.source.lines.size();
  out_.files.push_back(f.source.name);
  const int index = static_cast<int>(files_.size());
  files_.push_back(std::move(f));
  File& file = files_.back();
  // A program may be framed by '%' lines: the first non-blank line and a
  // later one, after which nothing is read.
  size_t first = 0;
  while (first < file.source.lines.size() && is_blank(file.source.lines[first]))
    ++first;
  const bool framed = first < file.source.lines.size() && is_percent_line(file.source.lines[first]);
  file.lines.reserve(file.source.lines.size());
  for (size_t i = 0; i < file.source.lines.size(); ++i) {
    const std::string& text = file.source.lines[i];
    if (framed && i > first && is_percent_line(text)) {
      file.end = i;
      break;
    }
    if (framed && i == first) {
      file.lines.push_back(lex_line("", file.source.name, static_cast<int>(i) + 1));
    } else {
      file.lines.push_back(lex_line(text, file.source.name, static_cast<int>(i) + 1));
    }
  }
  file.end = std::min(file.end, file.lines.size());
  file.owords.resize(file.lines.size());
  for (size_t i = 0; i < file.lines.size(); ++i) {
    file.owords[i] = scan_oword(file.lines[i]);
    if (file.owords[i] && file.owords[i]->keyword == OKeyword::kSub && !file.owords[i]->computed)
      subs_.emplace(file.owords[i]->label, std::make_pair(index, i));
    if (index == 0 && file.owords[i] && file.owords[i]->keyword == OKeyword::kFanucSub)
      fanuc_subs_.emplace(file.owords[i]->label, std::make_pair(index, i));
  }
  return index;
}

void ProgramRunner::run(SourceFile main_file) {
  add_file(std::move(main_file));
  frames_.push_back(Frame{});
  executor_.start_program();
  while (step()) {
  }
}

size_t ProgramRunner::find_forward(int file, size_t from, const std::string& label,
                                   std::initializer_list<OKeyword> kinds,
                                   const LexedLine& at) const {
  const File& f = files_[file];
  for (size_t i = from; i < f.end; ++i) {
    const auto& o = f.owords[i];
    if (!o || std::find(kinds.begin(), kinds.end(), o->keyword) == kinds.end()) continue;
    if (label_at(file, i) == label) return i;
  }
  std::string expected;
  for (OKeyword k : kinds)
    expected += std::string(expected.empty() ? "" : " or ") + keyword_name(k);
  fail(at, 1, "no matching " + label_text(label) + " " + expected + " found");
}

std::string ProgramRunner::label_at(int file, size_t index) const {
  const auto& o = files_[file].owords[index];
  if (!o->computed) return o->label;
  // As rs274 seeking a label: the line's label with the parameters of now.
  return scan_oword(files_[file].lines[index], &params_)->label;
}

std::optional<std::pair<int, size_t>> ProgramRunner::find_sub(const std::string& label,
                                                              const LexedLine& at) {
  if (auto it = subs_.find(label); it != subs_.end()) return it->second;
  // A definition under a computed label is known only once the flow has met
  // it: rs274 2.9 seeking a subroutine forward does not match one (measured).
  // o<name> call and o123 call: look for name.ngc (123.ngc) beside the
  // program, then on the path, as rs274 does.
  const bool named = !label.empty() && label.front() == '<';
  if (label.empty() || (named && label.size() < 3)) return std::nullopt;
  const std::string name = named ? label.substr(1, label.size() - 2) : label;
  std::vector<std::filesystem::path> dirs;
  dirs.push_back(std::filesystem::path(files_[0].source.name).parent_path());
  for (const auto& d : options_.subroutine_path)
    dirs.push_back(d);
  for (const auto& d : dirs) {
    std::error_code ec;
    for (const auto& candidate : {d / (name + ".ngc"), d / (name + ".NGC")}) {
      // A folder, a device or a pipe of that name is no subroutine file:
      // say so instead of "unknown subroutine" (and never read a pipe).
      if (std::filesystem::exists(candidate, ec) &&
          !std::filesystem::is_regular_file(candidate, ec))
        fail(at, 1,
             candidate.string() +
                 " is not a regular file (a folder, device or pipe), so "
                 "it cannot hold " +
                 label_text(label) + " sub");
      if (!std::filesystem::is_regular_file(candidate, ec)) continue;
      add_file(load_source(candidate));
      if (auto it = subs_.find(label); it != subs_.end()) return it->second;
      fail(at, 1, candidate.string() + " does not define " + label_text(label) + " sub");
    }
  }
  return std::nullopt;
}

void ProgramRunner::assign(const Block& block, const LexedLine& line) {
  for (const auto& a : block.assignments) {
    if (a.target.name.empty()) {
      params_.set(a.target.index, a.value);
    } else {
      if (params_.is_predefined(a.target.name))
        fail(line, a.column, "#<" + a.target.name + "> is a read-only predefined parameter");
      params_.set_named(a.target.name, a.value);
    }
  }
}

bool ProgramRunner::step() {
  Frame& frame = frames_.back();
  File& file = files_[frame.file];
  if (frame.pc >= file.end) {
    const LexedLine* last = file.lines.empty() ? nullptr : &file.lines.back();
    const int line = last ? last->line : 1;
    if (file.end < file.source.lines.size() && frames_.size() == 1) {
      emitter_.set_location(frame.file, line + 1);
      // Moves cutter compensation still holds are never sent, as in rs274.
      emitter_.discard_held();
      emitter_.emit(Finish{});
      emitter_.clear_block_number();
      emitter_.emit(OnReset{});
      emitter_.emit(OnReset{});
      return false;  // closing '%'
    }
    if (frames_.size() > 1)
      throw GcodeError(
          {file.source.name, line, 1},
          "end of file inside subroutine " + label_text(frame.label) + " (missing endsub)");
    throw GcodeError({file.source.name, line, 1},
                     "file ended with no program end (M2 or M30) and no closing '%'");
  }
  if (++blocks_ > options_.max_blocks)
    fail(file.lines[frame.pc], 1,
         "more than " + std::to_string(options_.max_blocks) +
             " blocks executed: an endless loop? (a longer program: --max-blocks N)");
  if (options_.progress && options_.progress_every_blocks > 0 &&
      blocks_ % options_.progress_every_blocks == 0)
    options_.progress(blocks_);
  const LexedLine& line = file.lines[frame.pc];
  if (frames_.size() == 1 && options_.on_watch_line && options_.watch_lines.count(line.line) &&
      watched_.insert(line.line).second)
    options_.on_watch_line(line.line, params_.values());
  if (line.text.empty() && line.sinumerik.empty()) {
    ++frame.pc;
    return true;
  }
  if (line.text[0] == '/' && options_.block_delete) {
    ++frame.pc;
    return true;
  }
  if (!line.text.empty() && line.text[0] == '%')
    fail(line, line.column[0], "'%' is only allowed alone on the first and last program lines");
  sync_state_parameters(state_, params_);
  emitter_.set_location(frame.file, line.line, block_number_of(line));
  if (frames_.size() > 1 || !frame.loops.empty()) {
    const Frame& top = frames_.front();
    const File& main = files_.front();
    emitter_.set_outer(frames_.size() > 1 ? main.lines[top.pc - 1].line : line.line,
                       top.loops.empty() ? 0 : main.lines[top.loops.front().start].line);
  }
  const Block block = read_block(line, params_, options_.has_b);
  assign(block, line);
  if (block.o) {
    control(*block.o, line);
    return true;
  }
  bool ends = false;
  if (fanuc_call_or_return(block, line, ends)) return !ends;
  ++frame.pc;
  return !executor_.execute(block, line);
}

bool ProgramRunner::fanuc_call_or_return(const Block& block, const LexedLine& line, bool& ends) {
  const bool call = block.has_m(980), back = block.has_m(990);
  if (!call && !back) return false;
  const int col = block.m.front().column;
  // rs274 ignores the other words of an M98 line (or refuses them) and
  // fails on an M99 line with anything else: truecut refuses both.
  bool others =
      !block.g.empty() || block.m.size() != 1 || block.has_polar() || !block.sinumerik.empty();
  for (char l = 'a'; l <= 'z'; ++l)
    if (block.has(l) && l != 'n' && !(call && (l == 'p' || l == 'l'))) others = true;
  const char* name = call ? "M98" : "M99";
  if (others)
    fail(line, col,
         std::string(name) + " must be alone on its line" + (call ? " (with P and L)" : "") +
             ": rs274 ignores or refuses the other words");
  Frame& frame = frames_.back();
  if (back) {
    if (frames_.size() == 1) {  // M99 in the main program ends it, as M2 in rs274
      ++frame.pc;
      executor_.end_program(false);
      ends = true;
      return true;
    }
    if (!frame.fanuc)
      fail(line, col, "M99 in the O-word subroutine " + label_text(frame.label) + " (use endsub)");
    if (frame.repeats_left >= 1) {  // M98 L: run the body again
      frame.repeats_left -= 1;
      frame.pc = frame.start;
      return true;
    }
    executor_.return_from_call(params_.call_level());  // M73
    params_.pop_call();
    frames_.pop_back();
    return true;
  }
  if (!block.has('p')) fail(line, col, "M98 needs P (the subprogram number)");
  const double p = block.value('p');
  if (p < 0 || p != std::floor(p) || p > 1e15)
    fail(line, col, "M98 P (the subprogram number) must be a whole number >= 0");
  double repeats = 1;
  if (block.has('l')) {
    repeats = block.value('l');
    if (repeats < 0 || repeats != std::floor(repeats))
      fail(line, col, "M98 L (the repeat count) must be a whole number >= 0");
  }
  char digits[32];
  std::snprintf(digits, sizeof digits, "%.0f", p);
  const std::string label = digits;
  const auto where = fanuc_subs_.find(label);
  if (where == fanuc_subs_.end()) {
    // rs274 reads the lines after the call looking for the subprogram and
    // stops at the first O-word it cannot read: that line's error first.
    const File& main = files_[0];
    for (size_t i = frame.file == 0 ? frame.pc + 1 : 0; i < main.end; ++i) {
      const std::string& text = main.lines[i].text;
      size_t k = 0;
      if (k < text.size() && text[k] == '/') ++k;
      if (k < text.size() && text[k] == 'n')
        while (++k < text.size() &&
               (std::isdigit(static_cast<unsigned char>(text[k])) || text[k] == '.')) {
        }
      if (k < text.size() && text[k] == 'o' && !main.owords[i])
        read_block(main.lines[i], params_, options_.has_b);  // throws the located error
    }
    fail(line, col, "M98 P" + label + ": no subprogram O" + label + " in the program");
  }
  ++frame.pc;
  if (repeats == 0) return true;
  if (frames_.size() > kMaxCallDepth)
    fail(line, col, "subprogram calls nested too deep (recursion?)");
  params_.push_shared_call();
  Frame sub{where->second.first, where->second.second + 1, label, {}};
  sub.fanuc = true;
  sub.repeats_left = repeats - 1;
  sub.start = sub.pc;
  frames_.push_back(sub);
  return true;
}

void ProgramRunner::control(const OWord& o, const LexedLine& line) {
  Frame& frame = frames_.back();
  const int fi = frame.file;
  const size_t pc = frame.pc;
  auto loop_index = [&](const std::string& label) -> int {
    for (int i = static_cast<int>(frame.loops.size()) - 1; i >= 0; --i)
      if (frame.loops[i].label == label) return i;
    return -1;
  };
  switch (o.keyword) {
    case OKeyword::kFanucSub:
      // Met in the flow of the program: a label, as in rs274.
      frame.pc = pc + 1;
      return;
    case OKeyword::kSub: {
      // A definition met in the flow of the program is skipped; one under a
      // computed label is known from here on, as in rs274. rs274 refuses to
      // meet a definition it already knows (called before it, or met again
      // in a loop): measured with rs274 2.9.
      if (!defined_subs_.insert(o.label).second)
        fail(line, o.column,
             label_text(o.label) +
                 " sub found in illegal location: the subroutine is already defined (called "
                 "before its definition, or the definition met again)");
      if (o.computed) subs_.emplace(o.label, std::make_pair(fi, pc));
      const size_t end = find_forward(fi, pc + 1, o.label, {OKeyword::kEndsub}, line);
      // rs274 refuses a definition inside another when it skips over it.
      for (size_t i = pc + 1; i < end; ++i)
        if (const auto& inner = files_[fi].owords[i]; inner && inner->keyword == OKeyword::kSub)
          fail(files_[fi].lines[i], inner->column,
               "nested subroutine definition: " + label_text(label_at(fi, i)) + " sub inside " +
                   label_text(o.label) + " sub");
      frame.pc = end + 1;
      return;
    }
    case OKeyword::kCall: {
      auto where = find_sub(o.label, line);
      if (!where) fail(line, o.column, "unknown subroutine " + label_text(o.label));
      if (frames_.size() > kMaxCallDepth)
        fail(line, o.column, "subroutine calls nested too deep (recursion?)");
      defined_subs_.insert(o.label);
      frame.pc = pc + 1;
      params_.push_call(o.args);
      frames_.push_back(Frame{where->first, where->second + 1, o.label, {}});
      return;
    }
    case OKeyword::kReturn:
    case OKeyword::kEndsub: {
      if (frames_.size() == 1)
        fail(line, o.column,
             label_text(o.label) + " " + keyword_name(o.keyword) + " outside a subroutine call");
      if (frame.fanuc)
        fail(line, o.column,
             label_text(o.label) + " " + keyword_name(o.keyword) + " in the subprogram O" +
                 frame.label + " (called by M98: use M99)");
      executor_.return_from_call(params_.call_level());  // M73
      params_.pop_call();
      frames_.pop_back();
      params_.set_named("_value", o.condition.value_or(0.0));
      params_.set_named("_value_returned", o.condition ? 1.0 : 0.0);
      return;
    }
    case OKeyword::kIf: {
      if (*o.condition != 0.0) {
        frame.pc = pc + 1;
        return;
      }
      size_t at = pc;
      while (true) {
        at = find_forward(fi, at + 1, o.label,
                          {OKeyword::kElseif, OKeyword::kElse, OKeyword::kEndif}, line);
        const OKeyword k = files_[fi].owords[at]->keyword;
        if (k != OKeyword::kElseif) break;
        const LexedLine& branch = files_[fi].lines[at];
        sync_state_parameters(state_, params_);
        const Block b = read_block(branch, params_, options_.has_b);
        if (*b.o->condition != 0.0) break;
      }
      frame.pc = at + 1;
      return;
    }
    case OKeyword::kElseif:
    case OKeyword::kElse:
      // Reached at the end of a branch that was taken.
      frame.pc = find_forward(fi, pc + 1, o.label, {OKeyword::kEndif}, line) + 1;
      return;
    case OKeyword::kEndif:
      frame.pc = pc + 1;
      return;
    case OKeyword::kDo: {
      const int li = loop_index(o.label);
      if (li < 0 || frame.loops[li].start != pc)
        frame.loops.push_back({o.label, OKeyword::kDo, pc});
      frame.pc = pc + 1;
      return;
    }
    case OKeyword::kWhile: {
      const int li = loop_index(o.label);
      if (li >= 0 && frame.loops[li].kind == OKeyword::kDo) {  // end of do ... while
        if (*o.condition != 0.0) {
          frame.pc = frame.loops[li].start + 1;
        } else {
          note_loop_end(static_cast<size_t>(li), pc);
          frame.loops.resize(li);
          frame.pc = pc + 1;
        }
        return;
      }
      if (*o.condition != 0.0) {
        if (li < 0 || frame.loops[li].start != pc)
          frame.loops.push_back({o.label, OKeyword::kWhile, pc});
        frame.pc = pc + 1;
      } else {
        const size_t end = find_forward(fi, pc + 1, o.label, {OKeyword::kEndwhile}, line);
        if (li >= 0) {
          note_loop_end(static_cast<size_t>(li), end);
          frame.loops.resize(li);
        }
        frame.pc = end + 1;
      }
      return;
    }
    case OKeyword::kEndwhile: {
      const int li = loop_index(o.label);
      if (li < 0) fail(line, o.column, label_text(o.label) + " endwhile without while");
      frame.pc = frame.loops[li].start;
      return;
    }
    case OKeyword::kRepeat: {
      const double n = std::floor(*o.condition);
      if (n <= 0) {
        frame.pc = find_forward(fi, pc + 1, o.label, {OKeyword::kEndrepeat}, line) + 1;
        return;
      }
      frame.loops.push_back({o.label, OKeyword::kRepeat, pc, n});
      frame.pc = pc + 1;
      return;
    }
    case OKeyword::kEndrepeat: {
      const int li = loop_index(o.label);
      if (li < 0) fail(line, o.column, label_text(o.label) + " endrepeat without repeat");
      if (--frame.loops[li].remaining > 0) {
        frame.pc = frame.loops[li].start + 1;
      } else {
        note_loop_end(static_cast<size_t>(li), pc);
        frame.loops.resize(li);
        frame.pc = pc + 1;
      }
      return;
    }
    case OKeyword::kBreak:
    case OKeyword::kContinue: {
      const int li = loop_index(o.label);
      if (li < 0)
        fail(line, o.column,
             label_text(o.label) + " " + keyword_name(o.keyword) + " outside its loop");
      const Loop loop = frame.loops[li];
      size_t end = 0;
      if (loop.kind == OKeyword::kWhile)
        end = find_forward(fi, pc + 1, o.label, {OKeyword::kEndwhile}, line);
      else if (loop.kind == OKeyword::kRepeat)
        end = find_forward(fi, pc + 1, o.label, {OKeyword::kEndrepeat}, line);
      else
        end = find_forward(fi, pc + 1, o.label, {OKeyword::kWhile}, line);
      if (o.keyword == OKeyword::kBreak) {
        note_loop_end(static_cast<size_t>(li), end);
        frame.loops.resize(li);
        frame.pc = end + 1;
      } else {
        frame.loops.resize(li + 1);
        frame.pc = loop.kind == OKeyword::kWhile ? loop.start : end;
      }
      return;
    }
  }
}

void ProgramRunner::note_loop_end(size_t li, size_t end) {
  if (frames_.size() != 1 || li != 0) return;
  const File& main = files_.front();
  const int first = main.lines[frames_.front().loops.front().start].line;
  const int last = main.lines[end].line;
  const auto [at, fresh] = out_.loop_last_lines.try_emplace(first, last);
  if (!fresh && at->second != last) at->second = 0;
}

}  // namespace truecut::interp
