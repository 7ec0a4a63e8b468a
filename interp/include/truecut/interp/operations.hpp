// CAM operation names taken from program comments, so a later stage can ask
// for "the moves of operation NAME".
//
// Rule: a comment, in parentheses or after ';', names an operation when its
// text (trimmed, case-insensitive keyword) is
//     OPERATION[ <number>]: NAME      e.g. (OPERATION: ROUGH), (Operation 3: Face1)
//     OP[ <number>]: NAME
//     TOOLPATH: NAME                  (PowerMill, CAMWorks)
//     JOB[ <number>]: NAME            (hyperMILL)
// The separator may be ':' or '='; NAME is the rest, trimmed, case kept. The
// operation stays active until the next such comment or the program end.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

std::optional<std::string> operation_from_comment(std::string_view comment);

// Operation names in program order, each once.
std::vector<std::string> operation_names(const CanonProgram& program);
// The motion calls (traverse, feed, arc) made within operation `name`.
std::vector<CanonCall> moves_of_operation(const CanonProgram& program, std::string_view name);

}  // namespace truecut::interp
