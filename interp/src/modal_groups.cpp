#include "modal_groups.hpp"

#include <cstdio>
#include <string>

namespace truecut::interp {

namespace {

struct GInfo {
  int code;
  GGroup group;
  const char* unsupported;  // non-null: known to LinuxCNC, not supported here
};

constexpr GInfo kGCodes[] = {
    {0, GGroup::kMotion, nullptr},
    {10, GGroup::kMotion, nullptr},
    {20, GGroup::kMotion, nullptr},
    {30, GGroup::kMotion, nullptr},
    {40, GGroup::kNonModal, nullptr},
    {50, GGroup::kMotion, nullptr},
    {51, GGroup::kMotion, nullptr},
    {52, GGroup::kMotion, nullptr},
    {53, GGroup::kMotion, nullptr},
    {70, GGroup::kLatheMode, "lathe diameter mode (G7)"},
    {80, GGroup::kLatheMode, "lathe radius mode (G8)"},
    {100, GGroup::kNonModal, nullptr},
    {170, GGroup::kPlane, nullptr},
    {171, GGroup::kPlane, "UV plane (G17.1)"},
    {180, GGroup::kPlane, nullptr},
    {181, GGroup::kPlane, "WU plane (G18.1)"},
    {190, GGroup::kPlane, nullptr},
    {191, GGroup::kPlane, "VW plane (G19.1)"},
    {200, GGroup::kUnits, nullptr},
    {210, GGroup::kUnits, nullptr},
    {280, GGroup::kNonModal, nullptr},
    {281, GGroup::kNonModal, nullptr},
    {300, GGroup::kNonModal, nullptr},
    {301, GGroup::kNonModal, nullptr},
    {330, GGroup::kMotion, nullptr},
    {331, GGroup::kMotion, nullptr},
    {382, GGroup::kMotion, nullptr},
    {383, GGroup::kMotion, nullptr},
    {384, GGroup::kMotion, nullptr},
    {385, GGroup::kMotion, nullptr},
    {400, GGroup::kCutterComp, nullptr},
    {410, GGroup::kCutterComp, nullptr},
    {411, GGroup::kCutterComp, nullptr},
    {420, GGroup::kCutterComp, nullptr},
    {421, GGroup::kCutterComp, nullptr},
    {430, GGroup::kToolLength, nullptr},
    {431, GGroup::kToolLength, nullptr},
    {432, GGroup::kToolLength, nullptr},
    {490, GGroup::kToolLength, nullptr},
    {520, GGroup::kNonModal, nullptr},
    {530, GGroup::kNonModal, nullptr},
    {540, GGroup::kCoordSystem, nullptr},
    {550, GGroup::kCoordSystem, nullptr},
    {560, GGroup::kCoordSystem, nullptr},
    {570, GGroup::kCoordSystem, nullptr},
    {580, GGroup::kCoordSystem, nullptr},
    {590, GGroup::kCoordSystem, nullptr},
    {591, GGroup::kCoordSystem, nullptr},
    {592, GGroup::kCoordSystem, nullptr},
    {593, GGroup::kCoordSystem, nullptr},
    {610, GGroup::kPathControl, nullptr},
    {611, GGroup::kPathControl, nullptr},
    {640, GGroup::kPathControl, nullptr},
    {700, GGroup::kMotion, "lathe finishing cycle (G70)"},
    {710, GGroup::kMotion, "lathe roughing cycle (G71)"},
    {711, GGroup::kMotion, "lathe roughing cycle (G71.1)"},
    {712, GGroup::kMotion, "lathe roughing cycle (G71.2)"},
    {720, GGroup::kMotion, "lathe facing cycle (G72)"},
    {721, GGroup::kMotion, "lathe facing cycle (G72.1)"},
    {722, GGroup::kMotion, "lathe facing cycle (G72.2)"},
    {730, GGroup::kMotion, nullptr},
    {740, GGroup::kMotion, nullptr},
    {760, GGroup::kMotion, "threading cycle (G76)"},
    {800, GGroup::kMotion, nullptr},
    {810, GGroup::kMotion, nullptr},
    {820, GGroup::kMotion, nullptr},
    {830, GGroup::kMotion, nullptr},
    {840, GGroup::kMotion, nullptr},
    {850, GGroup::kMotion, nullptr},
    {860, GGroup::kMotion, nullptr},
    {870, GGroup::kMotion, nullptr},
    {880, GGroup::kMotion, nullptr},
    {890, GGroup::kMotion, nullptr},
    {900, GGroup::kDistance, nullptr},
    {901, GGroup::kArcDistance, nullptr},
    {910, GGroup::kDistance, nullptr},
    {911, GGroup::kArcDistance, nullptr},
    {920, GGroup::kNonModal, nullptr},
    {921, GGroup::kNonModal, nullptr},
    {922, GGroup::kNonModal, nullptr},
    {923, GGroup::kNonModal, nullptr},
    {930, GGroup::kFeedMode, nullptr},
    {940, GGroup::kFeedMode, nullptr},
    {950, GGroup::kFeedMode, nullptr},
    {960, GGroup::kSpindleMode, nullptr},
    {970, GGroup::kSpindleMode, nullptr},
    {980, GGroup::kRetract, nullptr},
    {990, GGroup::kRetract, nullptr},
};

struct MInfo {
  int code;
  MGroup group;
  const char* unsupported;
};

constexpr MInfo kMCodes[] = {{0, MGroup::kStop, nullptr},
                             {10, MGroup::kStop, nullptr},
                             {20, MGroup::kStop, nullptr},
                             {30, MGroup::kSpindle, nullptr},
                             {40, MGroup::kSpindle, nullptr},
                             {50, MGroup::kSpindle, nullptr},
                             {60, MGroup::kToolChange, nullptr},
                             {70, MGroup::kCoolant, nullptr},
                             {80, MGroup::kCoolant, nullptr},
                             {90, MGroup::kCoolant, nullptr},
                             {190, MGroup::kSpindle, nullptr},
                             {300, MGroup::kStop, nullptr},
                             {480, MGroup::kOverride, nullptr},
                             {490, MGroup::kOverride, nullptr},
                             {500, MGroup::kOverride, nullptr},
                             {510, MGroup::kOverride, nullptr},
                             {520, MGroup::kOverride, nullptr},
                             {530, MGroup::kOverride, nullptr},
                             {600, MGroup::kStop, "pallet change pause (M60)"},
                             {610, MGroup::kToolChange, nullptr},
                             {620, MGroup::kUser, nullptr},
                             {630, MGroup::kUser, nullptr},
                             {640, MGroup::kUser, nullptr},
                             {650, MGroup::kUser, nullptr},
                             {660, MGroup::kUser, nullptr},
                             {670, MGroup::kUser, nullptr},
                             {680, MGroup::kUser, nullptr},
                             // M70-M73 share the spindle's group, as in LinuxCNC 2.9
                             {700, MGroup::kSpindle, nullptr},
                             {710, MGroup::kSpindle, nullptr},
                             {720, MGroup::kSpindle, nullptr},
                             {730, MGroup::kSpindle, nullptr},
                             // Fanuc-style subprograms: ProgramRunner runs M98 and M99 lines.
                             {980, MGroup::kStop, nullptr},
                             {990, MGroup::kStop, nullptr}};

std::string code_text(char letter, int code) {
  char buf[32];
  if (code % 10)
    std::snprintf(buf, sizeof buf, "%c%d.%d", letter, code / 10, code % 10);
  else
    std::snprintf(buf, sizeof buf, "%c%d", letter, code / 10);
  return buf;
}

[[noreturn]] void fail(const LexedLine& line, int column, const std::string& message) {
  throw GcodeError({*line.file, line.line, column}, message);
}

}  // namespace

ModalCodes::ModalCodes() {
  for (int i = 0; i < 16; ++i)
    g[i] = g_column[i] = -1;
  for (int i = 0; i < 11; ++i)
    m[i] = m_column[i] = -1;
}

ModalCodes check_codes(const Block& block, const LexedLine& line) {
  ModalCodes out;
  for (const auto& w : block.g) {
    const GInfo* info = nullptr;
    for (const auto& g : kGCodes)
      if (g.code == w.code) info = &g;
    if (!info) fail(line, w.column, "unknown G code " + code_text('G', w.code));
    if (info->unsupported)
      fail(line, w.column, code_text('G', w.code) + " " + info->unsupported + " is not supported");
    if (w.code == 530) continue;  // G53 combines with a motion code; see execution
    const int grp = static_cast<int>(info->group);
    if (info->group == GGroup::kNonModal) {
      if (out.non_modal_count++ > 0)
        fail(line, w.column,
             "two non-modal G codes on one line (" + code_text('G', out.g[0]) + " and " +
                 code_text('G', w.code) + ")");
    } else if (out.g[grp] >= 0) {
      fail(line, w.column,
           "two G codes from the same modal group on one line: " + code_text('G', out.g[grp]) +
               " and " + code_text('G', w.code));
    }
    out.g[grp] = w.code;
    out.g_column[grp] = w.column;
  }
  for (const auto& w : block.m) {
    const MInfo* info = nullptr;
    for (const auto& m : kMCodes)
      if (m.code == w.code) info = &m;
    if (!info) {
      if (w.code >= 1000 && w.code <= 1990)
        fail(line, w.column, "user M code " + code_text('M', w.code) + " is not supported");
      fail(line, w.column, "unknown M code " + code_text('M', w.code));
    }
    if (info->unsupported)
      fail(line, w.column, code_text('M', w.code) + " " + info->unsupported + " is not supported");
    const int grp = static_cast<int>(info->group);
    if (out.m[grp] >= 0)
      fail(line, w.column,
           "two M codes from the same modal group on one line: " + code_text('M', out.m[grp]) +
               " and " + code_text('M', w.code));
    out.m[grp] = w.code;
    out.m_column[grp] = w.column;
  }
  // BSPLINE / CSPLINE belong to the motion group like Sinumerik's G-group 1.
  for (const auto& k : block.sinumerik) {
    if (k.word != SinumerikWord::kBspline && k.word != SinumerikWord::kCspline) continue;
    const int grp = static_cast<int>(GGroup::kMotion);
    if (out.g[grp] >= 0)
      fail(line, k.column,
           out.g[grp] >= kBsplineCode ? std::string("two spline modes on one line")
                                      : "BSPLINE/CSPLINE and " + code_text('G', out.g[grp]) +
                                            " are both motion modes: only one per line");
    out.g[grp] = k.word == SinumerikWord::kBspline ? kBsplineCode : kCsplineCode;
    out.g_column[grp] = k.column;
  }
  return out;
}

}  // namespace truecut::interp
