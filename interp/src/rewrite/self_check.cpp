#include "self_check.hpp"

#include <cctype>
#include <cmath>

#include "truecut/interp/error.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::interp::rewrite {

namespace {

bool same_context(const CallContext& a, const CallContext& b) {
  return a.file == b.file && a.line == b.line && a.operation == b.operation && a.tool == b.tool &&
         a.units == b.units && a.feed_mode == b.feed_mode && a.inverse_time_f == b.inverse_time_f &&
         a.spline == b.spline && a.tcp == b.tcp && a.g5x_mm == b.g5x_mm && a.g92_mm == b.g92_mm &&
         a.tool_offset_mm == b.tool_offset_mm;
}

// Calls printed alike, a zero's sign apart (-0.000000000 is where 0 is).
bool same_text(const std::string& a, const std::string& b) {
  if (a == b) return true;
  auto unsigned_zeros = [](std::string s) {
    for (size_t at = s.find("-0.000000000"); at != std::string::npos;
         at = s.find("-0.000000000", at)) {
      const size_t end = at + 12;
      if (end < s.size() && std::isdigit(static_cast<unsigned char>(s[end]))) {
        ++at;
        continue;
      }
      s.erase(at, 1);
    }
    return s;
  };
  return unsigned_zeros(a) == unsigned_zeros(b);
}

struct Entry {
  const CanonCall* call;
  double feed;  // SET_FEED_RATE in force
};

// A canned-cycle line: its feeds run over the written hole, and the deepest
// ends at the written bottom.
template <class Fail>
void check_cycle_line(int line, const RewrittenLine& rw, const std::vector<const CanonCall*>* moves,
                      const Fail& fail) {
  const int normal = rw.cycle_normal_axis;
  const Axes6& want = rw.expected.at(0);
  auto near = [](double a, double b) {
    return std::fabs(a - b) <= 1e-9 * std::max(1.0, std::fabs(b));
  };
  const Axes6* deepest = nullptr;
  if (moves)
    for (const CanonCall* c : *moves) {
      const auto* f = std::get_if<StraightFeed>(&c->op);
      if (!f) continue;
      for (int ax = 0; ax < 3; ++ax)
        if (ax != normal && !near(f->end[ax], want[ax]))
          fail(line,
               "the written canned cycle feeds off its hole (incremental distance mode G91 "
               "active?)");
      // G87 back bores upwards: its cut, the highest feed, is the one written.
      if (!deepest || (rw.context.canned_cycle == 870 ? f->end[normal] > (*deepest)[normal]
                                                      : f->end[normal] < (*deepest)[normal]))
        deepest = &f->end;
      if (c->context.operation != rw.context.operation || c->context.tool != rw.context.tool)
        fail(line, "the written canned cycle runs in another mode than the original");
    }
  if (!deepest) return fail(line, "the written canned cycle makes no feed move");
  if (!near((*deepest)[normal], want[normal]))
    fail(line, "the written canned cycle does not reach its written bottom");
}

}  // namespace

void check_rewrite(const std::string& text, const CheckInput& in) {
  const CanonProgram out = Interpreter(in.options).run_text(text, in.name);
  // A call of the original at its own file (the program or a subroutine file).
  auto fail_at = [&](const CallContext& at, const std::string& what) {
    const std::string& file = at.file > 0 && at.file < static_cast<int>(in.original.files.size())
                                  ? in.original.files[static_cast<std::size_t>(at.file)]
                                  : in.name;
    throw GcodeError({file, at.line, 0}, "cannot be rewritten: " + what);
  };
  auto fail = [&](int line, const std::string& what) {
    CallContext at;
    at.line = line;
    fail_at(at, what);
  };
  // Where a call of the new program comes from, in words that cannot be
  // mistaken for a line of the original program.
  auto where_new = [&](const CanonCall& c, bool mapped_to_original) -> std::string {
    const std::string line = "line " + std::to_string(c.context.line);
    if (c.context.file != 0)
      return line + " of " +
             (c.context.file < static_cast<int>(out.files.size())
                  ? out.files[static_cast<std::size_t>(c.context.file)]
                  : std::string("a subroutine file"));
    return mapped_to_original ? line : line + " of the new program";
  };

  // Expanded loops and calls: first line -> last.
  std::map<int, int> expanded;
  for (const auto& [line, rw] : in.rewritten)
    if (rw.last_line > 0) expanded.emplace(line, rw.last_line);
  auto in_expansion = [&](const CallContext& c) {
    auto it = expanded.upper_bound(c.outer_line);
    return it != expanded.begin() && c.outer_line <= std::prev(it)->second;
  };

  std::vector<Entry> kept_in, kept_out;
  double feed = 0;
  for (const CanonCall& c : in.original.calls) {
    if (const auto* f = std::get_if<SetFeedRate>(&c.op)) feed = f->units_per_minute;
    if (c.context.file == 0 && in.rewritten.count(c.context.line)) continue;
    if (!expanded.empty() && in_expansion(c.context)) continue;
    kept_in.push_back({&c, feed});
  }
  std::map<int, std::vector<const CanonCall*>> moves_out;  // by original line
  std::map<int, std::vector<double>> feeds_out;            // feed in force at each
  std::map<int, std::vector<std::string>> others_out;      // expansions' other calls
  std::vector<CanonCall> mapped;
  std::vector<std::string> where_out;  // per mapped call
  mapped.reserve(out.calls.size());
  feed = 0;
  std::vector<double> feeds;
  for (const CanonCall& c : out.calls) {
    if (const auto* f = std::get_if<SetFeedRate>(&c.op)) feed = f->units_per_minute;
    if (c.context.file != 0 || c.context.line < 1 ||
        c.context.line > static_cast<int>(in.origin.size())) {
      where_out.push_back(where_new(c, false));
      mapped.push_back(c);
      feeds.push_back(feed);
      continue;
    }
    const OutputLine& o = in.origin.at(c.context.line - 1);
    if (o.kind == OutputLine::kVerbatim) {
      CanonCall m = c;
      m.context.line = o.source_line;
      where_out.push_back(where_new(m, true));
      mapped.push_back(std::move(m));
      feeds.push_back(feed);
    } else if (o.kind == OutputLine::kMove && is_motion(c.op)) {
      moves_out[o.source_line].push_back(&c);
      feeds_out[o.source_line].push_back(feed);
    } else if (o.kind == OutputLine::kMove && !std::holds_alternative<SetFeedRate>(c.op) &&
               !(std::holds_alternative<Comment>(c.op) &&
                 is_interpreter_note(std::get<Comment>(c.op)))) {
      others_out[o.source_line].push_back(format_rs274(c.op, check_format()));
    }
  }
  for (size_t i = 0; i < mapped.size(); ++i)
    kept_out.push_back({&mapped[i], feeds[i]});
  std::vector<std::string> kept_where = std::move(where_out);

  const FormatOptions fmt = check_format();
  const size_t n = std::min(kept_in.size(), kept_out.size());
  for (size_t i = 0; i < n; ++i) {
    const CanonCall& a = *kept_in[i].call;
    const CanonCall& b = *kept_out[i].call;
    const bool same = same_text(format_rs274(a.op, fmt), format_rs274(b.op, fmt)) &&
                      same_context(a.context, b.context) &&
                      (!is_motion(a.op) || kept_in[i].feed == kept_out[i].feed);
    if (!same)
      fail_at(a.context, "the new program does not reproduce " + format_rs274(a.op, fmt) +
                             " of this line (got " + format_rs274(b.op, fmt) + " at " +
                             kept_where[i] + "); a modal state set by the rewritten moves differs");
  }
  if (kept_in.size() != kept_out.size())
    fail_at(n < kept_in.size() ? kept_in[n].call->context : CallContext{},
            "the new program makes " + std::to_string(kept_out.size()) +
                " calls outside the rewritten lines, the original " +
                std::to_string(kept_in.size()));

  if (in.returns)
    for (const auto& [line, want] : *in.returns) {
      const auto it = moves_out.find(line);
      const CanonOp* op =
          it == moves_out.end() || it->second.size() != 1 ? nullptr : &it->second[0]->op;
      const auto* f = op ? std::get_if<StraightFeed>(op) : nullptr;
      const auto* t = op ? std::get_if<StraightTraverse>(op) : nullptr;
      const char* what = want.traverse ? "G0" : "G1";
      if (want.traverse ? !t : !f) {
        fail(line, std::string("the ") + what +
                       " back to the original point before this line is not one such move");
        continue;
      }
      const Axes6& end = want.traverse ? t->end : f->end;
      for (int ax = 0; ax < 6; ++ax)
        if (std::fabs(end[ax] - want.end[ax]) > 1e-9 * std::max(1.0, std::fabs(want.end[ax])))
          fail(line, std::string("the ") + what +
                         " back to the original point before this line comes out at " +
                         format_rs274(*op, fmt));
    }
  for (const auto& [line, rw] : in.rewritten) {
    const auto it = moves_out.find(line);
    const size_t got = it == moves_out.end() ? 0 : it->second.size();
    if (rw.cycle_normal_axis >= 0) {
      check_cycle_line(line, rw, got == 0 ? nullptr : &it->second, fail);
      continue;
    }
    if (rw.last_line > 0) {
      if (const std::vector<std::string>& made = others_out[line]; made != rw.others) {
        // The first call that differs, as rs274 prints it.
        size_t k = 0;
        while (k < made.size() && k < rw.others.size() && made[k] == rw.others[k])
          ++k;
        const std::string want = k < rw.others.size() ? rw.others[k] : "nothing more";
        const std::string have = k < made.size() ? made[k] : "nothing more";
        fail(line, "the expanded lines do not make the original's calls other than moves: " + have +
                       " where the original makes " + want + " (call " + std::to_string(k + 1) +
                       " of them)");
      }
      if (got != rw.expected.size())
        fail(line, std::to_string(got) + " moves from the expanded lines, expected " +
                       std::to_string(rw.expected.size()));
      const std::vector<double>& feeds = feeds_out[line];
      for (size_t k = 0; k < got; ++k) {
        const CanonCall& c = *it->second[k];
        const bool traverse = rw.traverse_at[k] != 0;
        const auto* f = std::get_if<StraightFeed>(&c.op);
        const auto* t = std::get_if<StraightTraverse>(&c.op);
        if (traverse ? !t : !f) fail(line, "an expanded line made another kind of move");
        const Axes6& end = traverse ? t->end : f->end;
        for (int ax = 0; ax < 6; ++ax)
          if (std::fabs(end[ax] - rw.expected[k][ax]) > 1e-9 * std::max(1.0, std::fabs(end[ax])))
            fail(line, "an expanded move comes out at " + format_rs274(c.op, fmt));
        const CallContext& want = rw.contexts[rw.context_at[k]];
        if (c.context.tcp != want.tcp || c.context.feed_mode != want.feed_mode ||
            c.context.operation != want.operation || c.context.tool != want.tool ||
            c.context.units != want.units || c.context.g5x_mm != want.g5x_mm ||
            c.context.g92_mm != want.g92_mm || c.context.tool_offset_mm != want.tool_offset_mm)
          fail(line, "an expanded move runs in another mode than the original (" +
                         format_rs274(c.op, fmt) + ")");
        // In G93 the feed is the line's own F (its share of the move's time).
        const double feed_k =
            want.feed_mode == FeedMode::kInverseTime ? c.context.inverse_time_f : feeds[k];
        if (!traverse && feed_k != rw.feed_at[k])
          fail(line, "an expanded move runs at another feed than the original (" +
                         format_rs274(c.op, fmt) + ")");
      }
      continue;
    }
    if (got != rw.expected.size())
      fail(line, std::to_string(got) + " moves from the written G1 lines, expected " +
                     std::to_string(rw.expected.size()));
    for (size_t k = 0; k < got; ++k) {
      const CanonCall& c = *it->second[k];
      const auto* f = std::get_if<StraightFeed>(&c.op);
      const auto* t = std::get_if<StraightTraverse>(&c.op);
      if (rw.traverse ? !t : !f) fail(line, "a written line made another kind of move");
      const Axes6& end = rw.traverse ? t->end : f->end;
      for (int ax = 0; ax < 6; ++ax)
        if (std::fabs(end[ax] - rw.expected[k][ax]) > 1e-9 * std::max(1.0, std::fabs(end[ax])))
          fail(line, "a written G1 point comes out at " + format_rs274(c.op, fmt) +
                         " (incremental distance mode G91 active?)");
      if (c.context.tcp != rw.context.tcp || c.context.feed_mode != rw.context.feed_mode ||
          c.context.operation != rw.context.operation || c.context.tool != rw.context.tool)
        fail(line, "the written G1 lines run in another mode than the original move");
    }
  }
}

}  // namespace truecut::interp::rewrite
