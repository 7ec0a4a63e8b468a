#include "expansion.hpp"

#include <optional>
#include <set>

#include "../block.hpp"
#include "../line_lexer.hpp"
#include "line_words.hpp"
#include "truecut/interp/error.hpp"

namespace truecut::interp::rewrite {

namespace {

std::optional<OWord> oword_of(const std::vector<RawLine>& raw, const std::string& name, int line) {
  try {
    return scan_oword(lex_line(raw.at(static_cast<std::size_t>(line) - 1).content, name, line));
  } catch (const GcodeError&) {
    return std::nullopt;  // not an O-word line the interpreter would read
  }
}

std::string label_text(const OWord& o) {
  return "o" + o.label;
}

// "the call o<name> call", "the subprogram call M98 P300 L2": the calling
// line's words, without comments (the note is a comment itself).
std::string call_text(const std::vector<RawLine>& raw, const std::string& name, int line) {
  const std::optional<OWord> o = oword_of(raw, name, line);
  if (o && o->keyword == OKeyword::kCall) return "the call " + label_text(*o) + " call";
  std::string words = raw.at(static_cast<std::size_t>(line) - 1).content;
  words = words.substr(0, words.find_first_of("(;"));
  const auto b = words.find_first_not_of(" \t"), e = words.find_last_not_of(" \t");
  return b == std::string::npos ? "the subprogram call"
                                : "the subprogram call " + words.substr(b, e - b + 1);
}

// The last line of the loop that starts at `start` (its endwhile, the while
// of a do, its endrepeat). A loop under a computed label (o[#1] while) ends
// where the interpreter's run of it ended: its closing line's label is
// known only with the parameters of that moment.
int loop_end(const CanonProgram& program, const std::vector<RawLine>& raw, const std::string& name,
             int start, std::string& what) {
  const std::optional<OWord> open = oword_of(raw, name, start);
  if (!open)
    throw GcodeError({name, start, 0}, "no loop starts at this line: it cannot be expanded");
  OKeyword closing = OKeyword::kEndwhile;
  const char* shape = "while ... endwhile";
  if (open->keyword == OKeyword::kDo) closing = OKeyword::kWhile, shape = "do ... while";
  if (open->keyword == OKeyword::kRepeat)
    closing = OKeyword::kEndrepeat, shape = "repeat ... endrepeat";
  if (open->computed) {
    // The label as written: from the O word to the next blank.
    const std::string& text = raw.at(static_cast<std::size_t>(start) - 1).content;
    const std::size_t from = open->column > 0 ? static_cast<std::size_t>(open->column) - 1
                                              : text.find_first_not_of(" \t");
    const std::string label = text.substr(from, text.find_first_of(" \t", from) - from);
    what = "the loop " + label + " " + shape;
    const auto ended = program.loop_last_lines.find(start);
    if (ended == program.loop_last_lines.end() || ended->second <= start)
      throw GcodeError({name, start, 0},
                       what +
                           " (a computed label) did not end in a way the interpreter saw once "
                           "(the program ended inside it, or its runs ended at different "
                           "lines): its end cannot be found to expand it");
    return ended->second;
  }
  what = "the loop " + label_text(*open) + " " + shape;
  for (int line = start + 1; line <= static_cast<int>(raw.size()); ++line) {
    const std::optional<OWord> o = oword_of(raw, name, line);
    if (o && !o->computed && o->label == open->label && o->keyword == closing) return line;
  }
  throw GcodeError({name, start, 0}, what + " has no end in the program: it cannot be expanded");
}

}  // namespace

Expansions find_expansions(const CanonProgram& program, const std::vector<RawLine>& raw,
                           const std::string& name, const std::string& operation,
                           const std::vector<NurbsBlock>& nurbs_blocks) {
  auto is_feed_of_op = [&](const CanonCall& c) {
    return c.context.operation == operation && is_motion(c.op) &&
           !std::holds_alternative<StraightTraverse>(c.op);
  };
  // Main-program lines of the operation's feeds that more than one block
  // runs (a loop, a subroutine of the program called twice).
  std::map<int, long> first_block;
  std::set<int> repeated;
  for (const CanonCall& c : program.calls)
    if (is_feed_of_op(c) && c.context.file == 0) {
      const auto [at, fresh] = first_block.try_emplace(c.context.line, c.context.executed_block);
      if (!fresh && at->second != c.context.executed_block) repeated.insert(c.context.line);
    }
  // Lines whose words are computed: a corrected move cannot keep them.
  std::map<int, bool> computed;
  auto is_computed = [&](int line) {
    const auto [at, fresh] = computed.try_emplace(line, false);
    if (fresh)
      at->second = line_has_parameter_or_expression(raw.at(static_cast<size_t>(line) - 1).content);
    return at->second;
  };
  Expansions out;
  bool synced = false;  // between START_SPEED_FEED_SYNC and its STOP (G33)
  for (const CanonCall& c : program.calls) {
    const CallContext& ctx = c.context;
    if (const auto* sync = std::get_if<SpeedFeedSync>(&c.op)) synced = sync->on;
    if (!is_feed_of_op(c)) continue;
    std::string why;
    if (ctx.file != 0)
      why = "feed moves of operation '" + operation + "' in a subroutine file";
    else if (repeated.count(ctx.line))
      why = "feed moves of operation '" + operation + "' run more than once";
    else if (ctx.line >= 1 && ctx.line <= static_cast<int>(raw.size()) && is_computed(ctx.line))
      why = "a feed move of operation '" + operation + "' with parameters or expressions";
    else if (ctx.canned_cycle != 0 && ctx.line >= 1 && ctx.line <= static_cast<int>(raw.size()) &&
             line_has_polar_word(raw[static_cast<size_t>(ctx.line) - 1].content))
      why = "a canned cycle of operation '" + operation + "' in polar coordinates";
    else if (ctx.incremental)
      why = "a feed move of operation '" + operation + "' in G91, incremental distance";
    else if (synced)
      why = "a G33 threading move of operation '" + operation + "', written as one G33 line";
    else
      continue;
    const int outer = ctx.outer_loop_line > 0 ? ctx.outer_loop_line : ctx.outer_line;
    if (outer < 1 || outer > static_cast<int>(raw.size()) || out.count(outer)) continue;
    Expansion e;
    e.first_line = e.last_line = outer;
    e.why = why;
    if (ctx.outer_loop_line > 0) {
      e.last_line = loop_end(program, raw, name, outer, e.what);
    } else {
      e.what = ctx.file == 0 && ctx.line == outer ? std::string("the line")
                                                  : call_text(raw, name, outer);
    }
    for (int line = e.first_line; line <= e.last_line; ++line) {
      const std::optional<OWord> o = oword_of(raw, name, line);
      if (o && o->keyword == OKeyword::kSub)
        throw GcodeError({name, line, 0}, "subroutine definition inside " + e.what +
                                              ", which the rewrite expands (" + why +
                                              "): move the definition out of it");
    }
    out.emplace(outer, std::move(e));
  }
  for (const NurbsBlock& b : nurbs_blocks) {
    if (expansion_at(out, b.outer_line)) continue;  // inside a loop or call written out
    Expansion e;
    e.why = "a NURBS block of operation '" + operation + "' spans several lines";
    if (b.outer_line >= b.first_line && b.outer_line <= b.last_line) {
      e.first_line = b.first_line;
      e.last_line = b.last_line;
      e.what = "the NURBS block G5.2 ... G5.3";
    } else {
      e.first_line = e.last_line = b.outer_line;
      e.what = call_text(raw, name, b.outer_line);
    }
    out.emplace(e.first_line, std::move(e));
  }
  return out;
}

const Expansion* expansion_at(const Expansions& expansions, int outer_line) {
  auto it = expansions.upper_bound(outer_line);
  if (it == expansions.begin()) return nullptr;
  --it;
  return outer_line <= it->second.last_line ? &it->second : nullptr;
}

}  // namespace truecut::interp::rewrite
