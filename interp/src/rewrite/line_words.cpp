#include "line_words.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include "line_lexer.hpp"

namespace truecut::interp::rewrite {

namespace {

bool keep_g(int code) {  // code x10
  static const int kKeep[] = {170, 180, 190, 200, 210, 400, 430, 490, 540, 550, 560, 570, 580, 590,
                              591, 592, 593, 610, 611, 640, 900, 901, 911, 930, 940, 970, 980, 990};
  return std::find(std::begin(kKeep), std::end(kKeep), code) != std::end(kKeep);
}

bool keep_m(int code) {  // M3 M4 M5 M6 M7 M8 M9, x10
  return code >= 30 && code <= 90 && code % 10 == 0;
}

std::string code_name(char letter, int code) {
  std::string s(1, letter);
  s += std::to_string(code / 10);
  if (code % 10) s += "." + std::to_string(code % 10);
  return s;
}

}  // namespace

bool is_cycle_code(int code) {  // G73, G74, G76 excluded, G81-G89, x10
  return code == 730 || code == 740 || (code >= 810 && code <= 890 && code % 10 == 0);
}

// cycle: the line of a canned cycle, whose hole and bottom (X Y Z) are cut
// out and everything else of the cycle (its G code, R, Q, P, L, F, G98/G99)
// kept.
LineWords split_line(const std::string& source, const std::string& file, int line_no, bool cycle,
                     bool back_boring = false) {
  const LexedLine lx = lex_line(source, file, line_no);
  const std::string& t = lx.text;
  auto column = [&](size_t i) { return i < lx.column.size() ? lx.column[i] : lx.end_column; };
  auto fail = [&](size_t i, const std::string& what) -> void {
    throw GcodeError({file, line_no, column(i)}, what + ": this move cannot be rewritten");
  };
  struct Span {
    size_t begin, end;  // in t
    char letter;
    int code;  // G/M code x10
  };
  std::vector<Span> words;
  LineWords out;
  size_t pos = 0;
  if (pos < t.size() && t[pos] == '/') out.block_delete = true, ++pos;
  while (pos < t.size()) {
    const char ch = t[pos];
    if (ch == '(') {
      pos = t.find(')', pos);
      pos = pos == std::string::npos ? t.size() : pos + 1;
      continue;
    }
    if (ch == ';') break;
    const bool polar = ch == '@' || ch == '^';  // polar radius and angle
    if (!polar && !std::isalpha(static_cast<unsigned char>(ch)))
      fail(pos, "parameter setting or expression");
    const size_t begin = pos++;
    while (pos < t.size() && (t[pos] == '+' || t[pos] == '-'))
      ++pos;
    const size_t num = pos;
    while (pos < t.size() && (std::isdigit(static_cast<unsigned char>(t[pos])) || t[pos] == '.'))
      ++pos;
    if (pos == num || (pos < t.size() && (t[pos] == '#' || t[pos] == '[')))
      fail(begin, std::string(polar ? "polar coordinate " : "word ") +
                      static_cast<char>(std::toupper(ch)) + " with a parameter or expression");
    int code = 0;
    if (ch == 'g' || ch == 'm')
      code = static_cast<int>(
          std::lround(std::strtod(t.substr(num, pos - num).c_str(), nullptr) * 10));
    words.push_back({begin, pos, ch, code});
  }
  bool g64 = false, g5 = false;  // P is G64's tolerance; Q is G5's control vector
  for (const Span& w : words) {
    if (w.letter == 'g' && w.code == 640) g64 = true;
    if (w.letter == 'g' && (w.code == 50 || w.code == 51)) g5 = true;
  }

  std::vector<bool> remove(words.size(), false);
  bool keeps_something =
      !lx.sinumerik.empty() || t.find('(') != std::string::npos || t.find(';') != std::string::npos;
  for (size_t k = 0; k < words.size(); ++k) {
    const Span& w = words[k];
    if (cycle) {
      const bool keep_word = w.letter == 'r' || w.letter == 'q' || w.letter == 'p' ||
                             w.letter == 'l' || w.letter == 'f' || w.letter == 'n' ||
                             w.letter == 's' || w.letter == 't' || w.letter == 'h' ||
                             (back_boring && (w.letter == 'i' || w.letter == 'j'));
      if (w.letter == 'x' || w.letter == 'y' || w.letter == 'z' ||
          (back_boring && w.letter == 'k')) {
        remove[k] = true;
        continue;
      }
      if (w.letter == '@' || w.letter == '^') fail(w.begin, "polar coordinate in a canned cycle");
      if (w.letter == 'g' && w.code == 910) fail(w.begin, "G91 (incremental distance)");
      if (w.letter == 'g' && !is_cycle_code(w.code) && !keep_g(w.code))
        fail(w.begin, code_name('G', w.code) + " beside a canned cycle");
      if (w.letter == 'm' && !keep_m(w.code))
        fail(w.begin, code_name('M', w.code) + " beside a canned cycle");
      if (w.letter != 'g' && w.letter != 'm' && !keep_word)
        fail(w.begin, std::string("word ") + static_cast<char>(std::toupper(w.letter)) +
                          " beside a canned cycle");
      if (w.letter != 'n') keeps_something = true;
      continue;
    }
    switch (w.letter) {
      case 'g':
        if (w.code == 0 || w.code == 10 || w.code == 20 || w.code == 30 || w.code == 50 ||
            w.code == 51) {
          remove[k] = true;
          out.explicit_motion = true;
        } else if (w.code == 530) {
          // A move in machine coordinates: its end is written in the program's
          // coordinates, where the interpreter put it (the same move).
          remove[k] = true;
        } else if (w.code == 410 || w.code == 411 || w.code == 420 || w.code == 421) {
          remove[k] = true;  // the rewrite writes compensated moves (docs/gcode.md)
          out.cutter_comp = true;
        } else if (w.code == 910) {
          fail(w.begin, "G91 (incremental distance)");
        } else if (!keep_g(w.code)) {
          fail(w.begin, code_name('G', w.code) + " beside a move");
        }
        break;
      case 'm':
        if (!keep_m(w.code)) fail(w.begin, code_name('M', w.code) + " beside a move");
        break;
      // The move's end is written as X Y Z: polar words (the same end in
      // G90) go with the other axis words.
      case '@':
      case '^':
      case 'x':
      case 'y':
      case 'z':
      case 'i':
      case 'j':
      case 'k':
      case 'r':
      case 'f':
      case 'd':  // the radius or diameter of G41/G42 (G41.1/G42.1)
      case 'l':  // the tool orientation of G41.1/G42.1
        remove[k] = true;
        break;
      case 'a':
        remove[k] = true;
        out.has_a = true;
        break;
      case 'c':
        remove[k] = true;
        out.has_c = true;
        break;
      case 'p':
        remove[k] = !g64;
        break;
      case 'q':
        remove[k] = g5;
        break;
      case 'n':
      case 's':
      case 't':
      case 'h':
        break;
      default:
        fail(w.begin,
             std::string("word ") + static_cast<char>(std::toupper(w.letter)) + " beside a move");
    }
    if (!remove[k] && w.letter != 'n') keeps_something = true;
  }
  if (!keeps_something) return out;
  // Cut the removed words out of the source text by their columns.
  std::vector<bool> drop(source.size(), false);
  for (size_t k = 0; k < words.size(); ++k) {
    if (!remove[k]) continue;
    const int from = column(words[k].begin) - 1, to = column(words[k].end - 1);  // [from, to)
    int c = std::max(from, 0);
    for (; c < to && c < static_cast<int>(source.size()); ++c)
      drop[c] = true;
    // and the blanks after it, so "N40 G1 X8 (cut)" leaves "N40 (cut)"
    while (c < static_cast<int>(source.size()) && (source[c] == ' ' || source[c] == '\t'))
      drop[c++] = true;
  }
  for (size_t c = 0; c < source.size(); ++c)
    if (!drop[c]) out.residual.push_back(source[c]);
  while (!out.residual.empty() &&
         (out.residual.back() == ' ' || out.residual.back() == '\t' || out.residual.back() == '\r'))
    out.residual.pop_back();
  return out;
}

namespace {

// The line as the interpreter reads it (lower case, no blanks), without its
// comments; "" when it cannot be read.
std::string words_of_line(const std::string& source) {
  LexedLine lx;
  try {
    lx = lex_line(source, "", 0);
  } catch (const GcodeError&) {
    return {};
  }
  const std::string& t = lx.text;
  std::string words;
  for (size_t pos = 0; pos < t.size(); ++pos) {
    if (t[pos] == '(') {
      pos = t.find(')', pos);
      if (pos == std::string::npos) break;
      continue;
    }
    if (t[pos] == ';') break;
    words += t[pos];
  }
  return words;
}

// The G codes (x10) written on a line; empty when it cannot be read.
std::vector<int> g_codes_of_line(const std::string& source) {
  const std::string t = words_of_line(source);
  std::vector<int> codes;
  for (size_t pos = 0; pos < t.size(); ++pos) {
    if (t[pos] != 'g') continue;
    size_t end = pos + 1;
    while (end < t.size() && (std::isdigit(static_cast<unsigned char>(t[end])) || t[end] == '.'))
      ++end;
    if (end == pos + 1) continue;
    codes.push_back(static_cast<int>(
        std::lround(std::strtod(t.substr(pos + 1, end - pos - 1).c_str(), nullptr) * 10)));
  }
  return codes;
}

}  // namespace

bool line_has_g_code(const std::string& source, int code) {
  for (int c : g_codes_of_line(source))
    if (c == code) return true;
  return false;
}

namespace {

// Whether the line's text outside comments holds one of `chars`.
bool line_has_any_of(const std::string& source, const char* chars) {
  const std::string t = words_of_line(source);
  return t.find_first_of(chars) != std::string::npos;
}

}  // namespace

bool line_has_parameter_or_expression(const std::string& source) {
  return line_has_any_of(source, "#[");
}

bool line_has_polar_word(const std::string& source) {
  return line_has_any_of(source, "@^");
}

bool has_cutter_comp_code(const std::string& source) {
  for (int code : g_codes_of_line(source))
    if (code == 410 || code == 411 || code == 420 || code == 421) return true;
  return false;
}

LineWords split_move_line(const std::string& source, const std::string& file, int line_no) {
  return split_line(source, file, line_no, false);
}

LineWords split_cycle_line(const std::string& source, const std::string& file, int line_no,
                           bool back_boring) {
  return split_line(source, file, line_no, true, back_boring);
}

std::string with_words_before_comment(const std::string& residual, const std::string& words) {
  // A word never holds '(' or ';': the first one starts the comments.
  const size_t comment = residual.find_first_of("(;");
  std::string head = residual.substr(0, comment);
  while (!head.empty() && (head.back() == ' ' || head.back() == '\t'))
    head.pop_back();
  std::string out = head.empty() || head == "/" ? head + words : head + " " + words;
  if (comment != std::string::npos) out += " " + residual.substr(comment);
  return out;
}

int motion_code_of_line(const std::string& source) {
  int found = -1;
  for (int code : g_codes_of_line(source))
    if (code == 0 || code == 10 || code == 20 || code == 30 || code == 730 ||
        (code >= 800 && code <= 890 && code % 10 == 0))
      found = code;
  return found;
}

}  // namespace truecut::interp::rewrite
