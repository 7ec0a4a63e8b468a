#include "block.hpp"

#include <cctype>
#include <cmath>
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

namespace {

struct KeywordSpelling {
  const char* text;
  OKeyword keyword;
};
// Longer spellings first where one is a prefix of another.
constexpr KeywordSpelling kOKeywords[] = {
    {"endsub", OKeyword::kEndsub},     {"endif", OKeyword::kEndif},
    {"endwhile", OKeyword::kEndwhile}, {"endrepeat", OKeyword::kEndrepeat},
    {"elseif", OKeyword::kElseif},     {"else", OKeyword::kElse},
    {"sub", OKeyword::kSub},           {"call", OKeyword::kCall},
    {"return", OKeyword::kReturn},     {"if", OKeyword::kIf},
    {"while", OKeyword::kWhile},       {"do", OKeyword::kDo},
    {"repeat", OKeyword::kRepeat},     {"break", OKeyword::kBreak},
    {"continue", OKeyword::kContinue}};

std::string describe_letter(char l) {
  return std::string(1, static_cast<char>(std::toupper(l)));
}

// Moves the cursor past a computed label (an [expression] or a parameter
// reference such as #5, #<n>, ##1 or #[1+2]) without evaluating it.
void skip_computed_label(Cursor& c) {
  while (c.peek() == '#') {
    ++c.pos;
    if (c.peek() == '#') continue;
    if (c.peek() == '<') {
      while (!c.at_end() && c.peek() != '>')
        ++c.pos;
      if (c.at_end()) c.fail("parameter name not closed with '>'");
      ++c.pos;
      return;
    }
    if (c.peek() != '[') {
      while (std::isdigit(static_cast<unsigned char>(c.peek())) || c.peek() == '.')
        ++c.pos;
      return;
    }
  }
  if (c.peek() != '[') c.fail("O-word needs a number or <name>");
  int depth = 0;
  do {
    if (c.at_end()) c.fail("unbalanced brackets in the computed O-word label");
    if (c.peek() == '[') ++depth;
    if (c.peek() == ']') --depth;
    ++c.pos;
  } while (depth > 0);
}

// Reads an O-word label and keyword at the cursor (on 'o'). A computed label
// (o[...], o#n: LinuxCNC's indirection) is evaluated with params, as rs274
// reads it: a whole number, whatever the keyword. Without params (scanning
// ahead) it is only marked computed, to be evaluated when the line is met.
OWord read_oword_head(Cursor& c, const Parameters* params) {
  OWord o;
  o.column = c.column_at(c.pos);
  ++c.pos;
  if (c.peek() == '[' || c.peek() == '#') {
    o.computed = true;
    if (params) {
      const size_t at = c.pos;
      const double v = read_real_value(c, *params);
      const double r = std::round(v);  // rs274 allows 1e-4 off a whole number
      if (!(std::fabs(v - r) <= 1e-4 && std::fabs(r) <= 2147483647.0))
        c.fail_at(at, "computed O-word label " + rt::format_shortest(v) +
                          " is not a whole number (rs274: non integer value for integer)");
      o.label = std::to_string(static_cast<int>(r));
    } else {
      skip_computed_label(c);
    }
  } else if (c.peek() == '<') {
    const size_t open = c.pos;
    while (!c.at_end() && c.peek() != '>')
      o.label.push_back(c.line->text[c.pos++]);
    if (c.at_end()) c.fail_at(open, "O-word name not closed with '>'");
    o.label.push_back(c.line->text[c.pos++]);
  } else {
    while (std::isdigit(static_cast<unsigned char>(c.peek())))
      o.label.push_back(c.line->text[c.pos++]);
    if (o.label.empty()) c.fail("O-word needs a number or <name>");
    // o0100 and o100 are the same label.
    size_t nz = o.label.find_first_not_of('0');
    o.label = nz == std::string::npos ? "0" : o.label.substr(nz);
  }
  // A number alone (comments may follow): a Fanuc-style subprogram start.
  if (!o.computed && o.label.front() != '<' && (c.at_end() || c.peek() == '(' || c.peek() == ';')) {
    o.keyword = OKeyword::kFanucSub;
    return o;
  }
  // A name alone: a program's title (O<name>), a label in the flow as in rs274.
  if (o.label.front() == '<' && (c.at_end() || c.peek() == '(' || c.peek() == ';')) {
    o.keyword = OKeyword::kFanucSub;
    return o;
  }
  for (const auto& k : kOKeywords) {
    if (c.starts_with(k.text)) {
      o.keyword = k.keyword;
      c.pos += std::char_traits<char>::length(k.text);
      return o;
    }
  }
  c.fail(
      "unknown O-word keyword (expected sub, endsub, call, return, if, elseif, else, endif, "
      "while, endwhile, do, repeat, endrepeat, break or continue)");
}

void read_comment(Cursor& c, Block& b) {
  const int col = c.column_at(c.pos);
  if (c.peek() == ';') {
    b.comments.push_back({c.line->text.substr(c.pos + 1), col, true});
    c.pos = c.line->text.size();
    return;
  }
  size_t close = c.line->text.find(')', c.pos);
  b.comments.push_back({c.line->text.substr(c.pos + 1, close - c.pos - 1), col});
  c.pos = close + 1;
}

void skip_comments(Cursor& c, Block& b) {
  while (!c.at_end() && (c.peek() == '(' || c.peek() == ';'))
    read_comment(c, b);
}

void read_oword_rest(Cursor& c, Block& b, const Parameters& params) {
  OWord& o = *b.o;
  switch (o.keyword) {
    case OKeyword::kCall:
      while (true) {
        skip_comments(c, b);
        if (c.peek() != '[') break;
        o.args.push_back(read_expression(c, params));
      }
      break;
    case OKeyword::kIf:
    case OKeyword::kElseif:
    case OKeyword::kWhile:
    case OKeyword::kRepeat:
      if (c.peek() != '[') c.fail("expected a [condition] after the O-word keyword");
      o.condition = read_expression(c, params);
      break;
    case OKeyword::kReturn:
    case OKeyword::kEndsub:
      if (c.peek() == '[') o.condition = read_expression(c, params);
      break;
    default:
      break;
  }
  skip_comments(c, b);
  if (!c.at_end()) c.fail("unexpected text after the O-word");
}

void read_word(Cursor& c, Block& b, const Parameters& params, bool has_b) {
  const size_t at = c.pos;
  const char l = c.peek();
  const int col = c.column_at(at);
  if (l == '@' || l == '^') {  // polar radius and angle (LinuxCNC)
    ++c.pos;
    if (c.at_end() || c.peek() == '(' || c.peek() == ';')
      c.fail_at(at, std::string("word ") + l + " has no value");
    const double v = read_real_value(c, params);
    auto& slot = l == '@' ? b.polar_radius : b.polar_angle;
    // LinuxCNC takes the last of two; truecut refuses them like two X words.
    if (slot) c.fail_at(at, std::string("two ") + l + " words on one line");
    slot = Word{v, col};
    return;
  }
  if (!std::isalpha(static_cast<unsigned char>(l))) {
    if (l == '#') c.fail("parameter setting needs '=': #n = value");
    if (l == ']') c.fail("unbalanced brackets: ']' without '['");
    if (l == '[') c.fail("expression without a word letter");
    c.fail(std::string("unknown character '") + l + "'");
  }
  switch (l) {
    case 'b':
      if (!has_b)
        c.fail("B axis word: this machine has X Y Z A C (A/C table-table); B is rejected");
      break;
    case 'u':
    case 'v':
    case 'w':
      c.fail("unknown word " + describe_letter(l) + ": this machine has axes X Y Z A C");
    case 'o':
      c.fail("O-word must start the line");
    default:
      break;
  }
  ++c.pos;
  if (c.at_end() || c.peek() == '(' || c.peek() == ';')
    c.fail_at(at, "word " + describe_letter(l) + " has no value");
  const double v = read_real_value(c, params);
  if (l == 'g' || l == 'm') {
    const double tenths = v * 10.0;
    const double r = std::round(tenths);
    if (std::fabs(tenths - r) > 1e-3 || r < 0)
      c.fail_at(
          at, describe_letter(l) + " code must be a non-negative number with at most one decimal");
    if (r > 1e6)  // would not fit the int below; no G or M code is that large
      c.fail_at(at, describe_letter(l) + " code " + rt::format_shortest(v) + " does not exist");
    if (l == 'm' && static_cast<int>(r) % 10 != 0) c.fail_at(at, "M code must be an integer");
    (l == 'g' ? b.g : b.m).push_back({static_cast<int>(r), col});
    return;
  }
  auto& slot = b.letter[l - 'a'];
  if (slot) c.fail_at(at, "two " + describe_letter(l) + " words on one line");
  slot = Word{v, col};
}

}  // namespace

bool Block::has_g(int code) const {
  for (const auto& w : g)
    if (w.code == code) return true;
  return false;
}
bool Block::has_m(int code) const {
  for (const auto& w : m)
    if (w.code == code) return true;
  return false;
}

std::optional<OWord> scan_oword(const LexedLine& line, const Parameters* params) {
  Cursor c{&line};
  if (c.peek() == '/') ++c.pos;
  if (c.peek() == 'n') {
    ++c.pos;
    while (std::isdigit(static_cast<unsigned char>(c.peek())) || c.peek() == '.')
      ++c.pos;
  }
  if (c.peek() != 'o') return std::nullopt;
  if (params) return read_oword_head(c, params);
  try {
    return read_oword_head(c, nullptr);
  } catch (const GcodeError&) {
    return std::nullopt;
  }
}

Block read_block(const LexedLine& line, const Parameters& params, bool has_b) {
  Block b;
  b.line = line.line;
  b.sinumerik = line.sinumerik;
  Cursor c{&line};
  if (c.peek() == '/') {
    b.deleted = true;
    ++c.pos;
  }
  if (c.peek() == 'n') {  // line number: an integer, ignored
    const size_t at = c.pos;
    ++c.pos;
    bool digits = false;
    while (std::isdigit(static_cast<unsigned char>(c.peek()))) {
      ++c.pos;
      digits = true;
    }
    if (c.peek() == '.') {
      ++c.pos;
      while (std::isdigit(static_cast<unsigned char>(c.peek())))
        ++c.pos;
    }
    if (!digits) c.fail_at(at, "N word needs a line number");
  }
  if (c.peek() == 'o') {
    b.o = read_oword_head(c, &params);
    read_oword_rest(c, b, params);
    return b;
  }
  while (!c.at_end()) {
    const char ch = c.peek();
    if (ch == '(' || ch == ';') {
      read_comment(c, b);
    } else if (ch == '#') {
      const int col = c.column_at(c.pos);
      ParameterRef ref = read_parameter_ref(c, params);
      if (c.peek() != '=') c.fail("expected '=' after the parameter (parameter setting)");
      ++c.pos;
      if (!ref.name.empty() && params.is_predefined(ref.name))
        c.fail_at(ref.at, "#<" + ref.name + "> is a read-only predefined parameter");
      b.assignments.push_back({ref, read_real_value(c, params), col});
    } else {
      read_word(c, b, params, has_b);
    }
  }
  return b;
}

}  // namespace truecut::interp
