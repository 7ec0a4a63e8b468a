// Real values of RS274/NGC words: numbers, parameters (#5, #<name>, ##1,
// #[expr]), bracketed expressions with LinuxCNC's binary operators and
// precedence, and the unary functions (angles in degrees).
#pragma once

#include <string>

#include "cursor.hpp"
#include "parameters.hpp"

namespace truecut::interp {

// A number, parameter, [expression] or function call, with an optional sign.
double read_real_value(Cursor& c, const Parameters& params);
// A real value that must be an integer (within 1e-4), e.g. a parameter index.
int read_integer_value(Cursor& c, const Parameters& params);
// `[ ... ]`; the cursor must be on '['.
double read_expression(Cursor& c, const Parameters& params);

// Target of an assignment `#... = value`: a numbered index or a name.
struct ParameterRef {
  int index = 0;     // numbered parameter, when name is empty
  std::string name;  // named parameter (lower case)
  size_t at = 0;     // position of '#'
};
// Reads the reference after '#' (the cursor is on '#').
ParameterRef read_parameter_ref(Cursor& c, const Parameters& params);

}  // namespace truecut::interp
