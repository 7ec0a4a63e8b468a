// The words of a program line that carries a move to be rewritten, with
// their source columns, so the move's words can be cut out and the rest of
// the line (modal codes, spindle, coolant, comments ...) kept as written.
#pragma once

#include <string>
#include <vector>

#include "truecut/interp/error.hpp"

namespace truecut::interp::rewrite {

struct LineWords {
  bool block_delete = false;     // the line starts with '/'
  bool explicit_motion = false;  // G0 G1 G2 G3 on the line
  // The source line without the words of the move (G0..G3, X Y Z A C,
  // polar @ ^, I J K R, P of an arc, F), trailing blanks removed; empty when nothing
  // but an N number would remain.
  std::string residual;
  bool has_a = false, has_c = false;  // A or C word on the line
  bool cutter_comp = false;           // G41 G42 G41.1 G42.1 (removed with D and L)
};

// `source` is the line without its terminator. Throws GcodeError at the
// offending column for anything that cannot stay beside a rewritten move:
// parameters and expressions, G91, G4, G10, G28, G30, G92, M0 M1 M2
// M30 M60 and unknown words.
LineWords split_move_line(const std::string& source, const std::string& file, int line);

// The line of a canned cycle (G73 G74 G81-G89) without its X Y Z words;
// the cycle's other words (its G code, R Q P L F, G98/G99) and comments
// stay. Throws GcodeError as split_move_line, and for polar words.
// `back_boring` (G87): its K, the back-bore height, goes with X Y Z; its
// entry offset I J stays.
LineWords split_cycle_line(const std::string& source, const std::string& file, int line,
                           bool back_boring = false);

// residual with `words` inserted after its last word, before any comment.
std::string with_words_before_comment(const std::string& residual, const std::string& words);

// The motion-group G code (x10: G0 G1 G2 G3 G73 G80-G89) written on a line,
// -1 without one or when the line cannot be read. Never throws.
int motion_code_of_line(const std::string& source);

// Whether a line has the G code `code` (x10: 52 for G5.2). Never throws.
bool line_has_g_code(const std::string& source, int code);

// Whether a line's words use parameters or expressions ('#' or '[' outside
// comments; parameter settings included). Never throws.
bool line_has_parameter_or_expression(const std::string& source);
// Whether a line has polar words ('@' '^'). Never throws.
bool line_has_polar_word(const std::string& source);

// Whether a line has G41, G42, G41.1 or G42.1. Never throws.
bool has_cutter_comp_code(const std::string& source);

}  // namespace truecut::interp::rewrite
