// G and M codes: which modal group each belongs to, which ones truecut
// supports, and the per-block checks (one code per group, known codes).
#pragma once

#include "block.hpp"
#include "cursor.hpp"

namespace truecut::interp {

// Modal group numbers follow LinuxCNC's (0 = non-modal).
enum class GGroup {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedMode = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kRetract = 10,
  kCoordSystem = 12,
  kPathControl = 13,
  kSpindleMode = 14,
  kLatheMode = 15
};
enum class MGroup {
  kStop = 4,
  kToolChange = 6,
  kSpindle = 7,
  kCoolant = 8,
  kOverride = 9,
  kUser = 10
};

// Motion-group codes standing for BSPLINE and CSPLINE.
constexpr int kBsplineCode = 90010;
constexpr int kCsplineCode = 90020;

// G73, G74, G81-G89 (the canned cycles truecut runs).
constexpr bool is_canned_cycle(int code) {
  return code == 730 || code == 740 || (code >= 810 && code <= 890 && code % 10 == 0);
}

// Per-block result of the checks: the code of each group or -1.
struct ModalCodes {
  int g[16];
  int g_column[16];
  int m[11];
  int m_column[11];
  int non_modal_count = 0;  // G4, G10, G28, G30, G92.x (G53 apart)
  ModalCodes();
};

// Throws GcodeError for unknown or unsupported codes and for two codes of
// the same group on one line.
ModalCodes check_codes(const Block& block, const LexedLine& line);

}  // namespace truecut::interp
