#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "truecut/rt/hal.hpp"

namespace truecut::rt::hal {

const char* to_string(Type type) {
  switch (type) {
    case Type::kBit:
      return "bit";
    case Type::kFloat:
      return "float";
    case Type::kS32:
      return "s32";
    case Type::kU32:
      return "u32";
  }
  return "?";
}

const char* to_string(PinDir dir) {
  switch (dir) {
    case PinDir::kIn:
      return "IN";
    case PinDir::kOut:
      return "OUT";
    case PinDir::kIo:
      return "I/O";
  }
  return "?";
}

const char* to_string(ParamDir dir) {
  return dir == ParamDir::kRo ? "RO" : "RW";
}

Value Value::of_bit(bool v) {
  Value x;
  x.type = Type::kBit;
  x.b = v;
  return x;
}
Value Value::of_float(double v) {
  Value x;
  x.type = Type::kFloat;
  x.f = v;
  return x;
}
Value Value::of_s32(int32_t v) {
  Value x;
  x.type = Type::kS32;
  x.s = v;
  return x;
}
Value Value::of_u32(uint32_t v) {
  Value x;
  x.type = Type::kU32;
  x.u = v;
  return x;
}

double Value::as_double() const {
  switch (type) {
    case Type::kBit:
      return b ? 1.0 : 0.0;
    case Type::kFloat:
      return f;
    case Type::kS32:
      return s;
    case Type::kU32:
      return u;
  }
  return 0.0;
}

std::string Value::to_text() const {
  switch (type) {
    case Type::kBit:
      return b ? "TRUE" : "FALSE";
    case Type::kS32:
      return std::to_string(s);
    case Type::kU32:
      return std::to_string(u);
    case Type::kFloat: {
      char buf[32];
      auto res = std::to_chars(buf, buf + sizeof buf, f);
      return std::string(buf, res.ptr);
    }
  }
  return "?";
}

namespace {
[[noreturn]] void bad_value(Type type, const std::string& text, const char* why) {
  throw HalError("value '" + text + "' is not a valid " + to_string(type) + " (" + why + ")");
}
}  // namespace

Value parse_value(Type type, const std::string& text) {
  if (text.empty()) bad_value(type, text, "empty");
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  switch (type) {
    case Type::kBit: {
      if (text == "1" || text == "TRUE" || text == "true" || text == "True")
        return Value::of_bit(true);
      if (text == "0" || text == "FALSE" || text == "false" || text == "False")
        return Value::of_bit(false);
      bad_value(type, text, "expected 0, 1, TRUE or FALSE");
    }
    case Type::kFloat: {
      double v = std::strtod(begin, &end);
      if (end == begin || *end != '\0') bad_value(type, text, "not a number");
      if (errno == ERANGE && std::isinf(v)) bad_value(type, text, "out of range");
      if (!std::isfinite(v)) bad_value(type, text, "not finite");
      return Value::of_float(v);
    }
    case Type::kS32: {
      long long v = std::strtoll(begin, &end, 0);
      if (end == begin || *end != '\0') bad_value(type, text, "not an integer");
      if (errno == ERANGE || v < std::numeric_limits<int32_t>::min() ||
          v > std::numeric_limits<int32_t>::max())
        bad_value(type, text, "outside -2147483648..2147483647");
      return Value::of_s32(static_cast<int32_t>(v));
    }
    case Type::kU32: {
      if (text.find('-') != std::string::npos) bad_value(type, text, "negative");
      unsigned long long v = std::strtoull(begin, &end, 0);
      if (end == begin || *end != '\0') bad_value(type, text, "not an integer");
      if (errno == ERANGE || v > std::numeric_limits<uint32_t>::max())
        bad_value(type, text, "outside 0..4294967295");
      return Value::of_u32(static_cast<uint32_t>(v));
    }
  }
  bad_value(type, text, "unknown type");
}

}  // namespace truecut::rt::hal
