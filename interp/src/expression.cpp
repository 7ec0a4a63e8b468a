#include "expression.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kEqualTolerance = 1e-4;  // LinuxCNC's EQ/NE tolerance

enum class Op {
  kPower,
  kTimes,
  kDivide,
  kMod,
  kPlus,
  kMinus,
  kEq,
  kNe,
  kGt,
  kGe,
  kLt,
  kLe,
  kAnd,
  kOr,
  kXor,
  kNone
};

int precedence(Op op) {
  switch (op) {
    case Op::kPower:
      return 6;
    case Op::kTimes:
    case Op::kDivide:
    case Op::kMod:
      return 5;
    case Op::kPlus:
    case Op::kMinus:
      return 4;
    case Op::kEq:
    case Op::kNe:
    case Op::kGt:
    case Op::kGe:
    case Op::kLt:
    case Op::kLe:
      return 3;
    case Op::kAnd:
    case Op::kOr:
    case Op::kXor:
      return 2;
    case Op::kNone:
      return 0;
  }
  return 0;
}

struct Spelling {
  const char* text;
  Op op;
};
constexpr Spelling kOps[] = {{"**", Op::kPower}, {"*", Op::kTimes}, {"/", Op::kDivide},
                             {"mod", Op::kMod},  {"+", Op::kPlus},  {"-", Op::kMinus},
                             {"eq", Op::kEq},    {"ne", Op::kNe},   {"gt", Op::kGt},
                             {"ge", Op::kGe},    {"lt", Op::kLt},   {"le", Op::kLe},
                             {"and", Op::kAnd},  {"or", Op::kOr},   {"xor", Op::kXor}};

const char* spelling(Op op) {
  for (const auto& s : kOps)
    if (s.op == op) return s.text;
  return "?";
}

// Reads a binary operator at the cursor without consuming it; sets `len`.
Op peek_operator(const Cursor& c, size_t& len) {
  for (const auto& s : kOps) {
    if (c.starts_with(s.text)) {
      len = std::char_traits<char>::length(s.text);
      return s.op;
    }
  }
  len = 0;
  return Op::kNone;
}

// A result that overflowed (EXP[1000], 10**400, 1e300*1e300) is refused
// where it arises: nothing downstream can use an infinite coordinate.
double finite_or_fail(const Cursor& c, size_t at, double v, const std::string& what) {
  if (!std::isfinite(v)) c.fail_at(at, what + " overflows: the result is not a finite number");
  return v;
}

double apply_unchecked(const Cursor& c, size_t at, Op op, double a, double b) {
  switch (op) {
    case Op::kPower:
      if (a < 0 && std::floor(b) != b)
        c.fail_at(at, "attempt to raise a negative number to a non-integer power");
      return std::pow(a, b);
    case Op::kTimes:
      return a * b;
    case Op::kDivide:
      if (b == 0.0) c.fail_at(at, "division by zero");
      return a / b;
    case Op::kMod: {
      if (b == 0.0) c.fail_at(at, "division by zero (MOD 0)");
      double r = std::fmod(a, b);
      if (r < 0) r += std::fabs(b);
      return r;
    }
    case Op::kPlus:
      return a + b;
    case Op::kMinus:
      return a - b;
    case Op::kEq:
      return std::fabs(a - b) < kEqualTolerance ? 1.0 : 0.0;
    case Op::kNe:
      return std::fabs(a - b) >= kEqualTolerance ? 1.0 : 0.0;
    case Op::kGt:
      return a > b ? 1.0 : 0.0;
    case Op::kGe:
      return a >= b ? 1.0 : 0.0;
    case Op::kLt:
      return a < b ? 1.0 : 0.0;
    case Op::kLe:
      return a <= b ? 1.0 : 0.0;
    case Op::kAnd:
      return (a != 0.0 && b != 0.0) ? 1.0 : 0.0;
    case Op::kOr:
      return (a != 0.0 || b != 0.0) ? 1.0 : 0.0;
    case Op::kXor:
      return ((a != 0.0) != (b != 0.0)) ? 1.0 : 0.0;
    case Op::kNone:
      break;
  }
  return 0.0;
}

double apply(const Cursor& c, size_t at, Op op, double a, double b) {
  return finite_or_fail(c, at, apply_unchecked(c, at, op, a, b),
                        std::string("the operator ") + spelling(op));
}

double read_number(Cursor& c) {
  const size_t start = c.pos;
  if (c.peek() == '+' || c.peek() == '-') ++c.pos;
  bool digits = false, dot = false;
  while (!c.at_end()) {
    char ch = c.peek();
    if (std::isdigit(static_cast<unsigned char>(ch))) {
      digits = true;
    } else if (ch == '.' && !dot) {
      dot = true;
    } else {
      break;
    }
    ++c.pos;
  }
  if (!digits) c.fail_at(start, "bad number format: expected a number");
  return finite_or_fail(c, start,
                        std::strtod(c.line->text.substr(start, c.pos - start).c_str(), nullptr),
                        "this number (" + std::to_string(c.pos - start) + " characters)");
}

// After `#` + `<`: the name up to '>'.
std::string read_name(Cursor& c) {
  const size_t open = c.pos;
  ++c.pos;  // '<'
  std::string name;
  while (!c.at_end() && c.peek() != '>')
    name.push_back(c.line->text[c.pos++]);
  if (c.at_end()) c.fail_at(open, "named parameter not closed with '>'");
  ++c.pos;
  if (name.empty()) c.fail_at(open, "empty parameter name");
  return name;
}

double parameter_value(Cursor& c, const Parameters& params) {
  const size_t at = c.pos;
  ParameterRef ref = read_parameter_ref(c, params);
  if (!ref.name.empty()) {
    auto v = params.named(ref.name);
    if (!v) c.fail_at(at, "named parameter #<" + ref.name + "> is not defined");
    return *v;
  }
  return params.get(ref.index);
}

struct Function {
  const char* name;
  enum Kind {
    kAbs,
    kAcos,
    kAsin,
    kAtan,
    kCos,
    kExp,
    kFix,
    kFup,
    kLn,
    kRound,
    kSin,
    kSqrt,
    kTan,
    kExists
  } kind;
};
constexpr Function kFunctions[] = {
    {"abs", Function::kAbs},   {"acos", Function::kAcos},   {"asin", Function::kAsin},
    {"atan", Function::kAtan}, {"cos", Function::kCos},     {"exists", Function::kExists},
    {"exp", Function::kExp},   {"fix", Function::kFix},     {"fup", Function::kFup},
    {"ln", Function::kLn},     {"round", Function::kRound}, {"sin", Function::kSin},
    {"sqrt", Function::kSqrt}, {"tan", Function::kTan}};

const Function* peek_function(const Cursor& c) {
  for (const auto& f : kFunctions) {
    size_t n = std::char_traits<char>::length(f.name);
    if (c.starts_with(f.name) && c.peek(n) == '[') return &f;
  }
  return nullptr;
}

double call_function_unchecked(Cursor& c, const Parameters& params, const Function& f, size_t at) {
  c.pos += std::char_traits<char>::length(f.name);
  if (f.kind == Function::kExists) {
    // exists[#<name>]: 1 when the named parameter is defined. As in
    // LinuxCNC, exists[#n] (n a number or a parameter, ##1) is 1 when the
    // number n is a parameter number (1..5601): numbered parameters always
    // exist.
    const size_t open = c.pos;
    ++c.pos;
    if (c.peek() != '#') c.fail("EXISTS needs a parameter: exists[#<name>] or exists[#number]");
    ++c.pos;
    double exists = 0.0;
    if (c.peek() == '<') {
      exists = params.named(read_name(c)).has_value() ? 1.0 : 0.0;
    } else {
      exists = Parameters::valid_index(read_integer_value(c, params)) ? 1.0 : 0.0;
    }
    if (c.peek() != ']') c.fail_at(open, "missing ']' (unbalanced brackets)");
    ++c.pos;
    return exists;
  }
  double v = read_expression(c, params);
  switch (f.kind) {
    case Function::kAbs:
      return std::fabs(v);
    case Function::kAcos:
      if (v < -1.0 || v > 1.0) c.fail_at(at, "ACOS argument out of range [-1, 1]");
      return std::acos(v) / kDegToRad;
    case Function::kAsin:
      if (v < -1.0 || v > 1.0) c.fail_at(at, "ASIN argument out of range [-1, 1]");
      return std::asin(v) / kDegToRad;
    case Function::kAtan: {
      if (c.peek() != '/') c.fail("ATAN needs two arguments: atan[y]/[x]");
      ++c.pos;
      if (c.peek() != '[') c.fail("ATAN needs two arguments: atan[y]/[x]");
      double x = read_expression(c, params);
      return std::atan2(v, x) / kDegToRad;
    }
    case Function::kCos:
      return std::cos(v * kDegToRad);
    case Function::kExp:
      return std::exp(v);
    case Function::kFix:
      return std::floor(v);
    case Function::kFup:
      return std::ceil(v);
    case Function::kLn:
      if (v <= 0.0) c.fail_at(at, "LN of a zero or negative number");
      return std::log(v);
    case Function::kRound:
      return std::round(v);
    case Function::kSin:
      return std::sin(v * kDegToRad);
    case Function::kSqrt:
      if (v < 0.0) c.fail_at(at, "SQRT of a negative number");
      return std::sqrt(v);
    case Function::kTan:
      return std::tan(v * kDegToRad);
    case Function::kExists:
      break;
  }
  return 0.0;
}

double call_function(Cursor& c, const Parameters& params, const Function& f) {
  const size_t at = c.pos;
  std::string name = f.name;
  for (char& ch : name)
    ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return finite_or_fail(c, at, call_function_unchecked(c, params, f, at), name);
}

}  // namespace

ParameterRef read_parameter_ref(Cursor& c, const Parameters& params) {
  ParameterRef ref;
  ref.at = c.pos;
  ++c.pos;  // '#'
  if (c.peek() == '<') {
    ref.name = read_name(c);
    return ref;
  }
  // `###1` is #(#(#1)): each '#' reads a value as deep as a bracket does,
  // and counts against the same limit (a chain of 4000 overflowed the stack).
  if (++c.nesting > kMaxExpressionNesting)
    c.fail_at(ref.at, "parameter reference nested deeper than " +
                          std::to_string(kMaxExpressionNesting) +
                          " (brackets and '#' of '#' together)");
  const size_t at = c.pos;
  int index = read_integer_value(c, params);
  if (!Parameters::valid_index(index))
    c.fail_at(at, "parameter number #" + std::to_string(index) + " out of range (1..5601)");
  --c.nesting;
  ref.index = index;
  return ref;
}

double read_expression(Cursor& c, const Parameters& params) {
  const size_t open = c.pos;
  if (++c.nesting > kMaxExpressionNesting)
    c.fail_at(open, "expression nested deeper than " + std::to_string(kMaxExpressionNesting) +
                        " brackets");
  ++c.pos;  // '['
  std::vector<double> values;
  std::vector<std::pair<Op, size_t>> ops;
  auto reduce = [&] {
    double b = values.back();
    values.pop_back();
    double a = values.back();
    auto [op, at] = ops.back();
    ops.pop_back();
    values.back() = apply(c, at, op, a, b);
  };
  values.push_back(read_real_value(c, params));
  while (true) {
    if (c.at_end()) c.fail_at(open, "missing ']' (unbalanced brackets)");
    if (c.peek() == ']') {
      ++c.pos;
      break;
    }
    size_t len = 0;
    const size_t at = c.pos;
    Op op = peek_operator(c, len);
    if (op == Op::kNone) c.fail("expected an operator or ']' in expression");
    c.pos += len;
    while (!ops.empty() && precedence(ops.back().first) >= precedence(op))
      reduce();
    ops.push_back({op, at});
    values.push_back(read_real_value(c, params));
  }
  while (!ops.empty())
    reduce();
  --c.nesting;
  return values.back();
}

double read_real_value(Cursor& c, const Parameters& params) {
  if (c.at_end()) c.fail("missing value");
  const char ch = c.peek();
  if ((ch == '-' || ch == '+') && (c.peek(1) == '[' || c.peek(1) == '#' ||
                                   std::isalpha(static_cast<unsigned char>(c.peek(1))))) {
    ++c.pos;
    double v = read_real_value(c, params);
    return ch == '-' ? -v : v;
  }
  if (ch == '[') return read_expression(c, params);
  if (ch == '#') return parameter_value(c, params);
  if (std::isalpha(static_cast<unsigned char>(ch))) {
    if (const Function* f = peek_function(c)) return call_function(c, params, *f);
    c.fail(std::string("expected a value, found '") + ch + "'");
  }
  if (ch == ']') c.fail("unbalanced brackets: ']' without '['");
  return read_number(c);
}

int read_integer_value(Cursor& c, const Parameters& params) {
  const size_t at = c.pos;
  double v = read_real_value(c, params);
  double r = std::round(v);
  if (std::fabs(v - r) > 1e-4) c.fail_at(at, "value must be an integer");
  if (!(std::fabs(r) <= 2147483647.0))  // the int below; no parameter, L or P is that large
    c.fail_at(at, "value " + rt::format_shortest(v) + " is too large");
  return static_cast<int>(r);
}

}  // namespace truecut::interp
