// M62-M68 (digital and analog outputs, wait on an input), M19 (spindle
// orient) and M48-M53 (override switches), as LinuxCNC 2.9's rs274 runs
// them (docs/gcode.md "Outputs, inputs, orient and override switches").
#include <cmath>

#include "block_executor.hpp"
#include "system_parameters.hpp"

namespace truecut::interp {

namespace {

constexpr int kUserGroup = static_cast<int>(MGroup::kUser);
constexpr int kOverrideGroup = static_cast<int>(MGroup::kOverride);
// rs274 keeps the last M66 result here; standalone it reads every input as 0.
constexpr int kInputValue = 5399;
// M66 L: 0 immediate, 1 rise, 2 fall, 3 high, 4 low.
constexpr double kLargestWaitMode = 4;
// An output or input number larger than this is a typing error.
constexpr double kLargestIoIndex = 1000;

}  // namespace

int BlockExecutor::whole_word(char letter, double largest, const std::string& what) const {
  const double v = b_->value(letter);
  if (v < 0 || v != std::floor(v) || v > largest)
    fail(column_of(letter), what + " must be a whole number from 0 to " +
                                std::to_string(static_cast<long long>(largest)));
  return static_cast<int>(v);
}

void BlockExecutor::io_codes() {
  const int code = codes_.m[kUserGroup];
  if (code < 620 || code > 680) return;
  const int col = codes_.m_column[kUserGroup];
  const std::string name = "M" + std::to_string(code / 10);
  if (code >= 620 && code <= 650) {
    if (!b_->has('p')) fail(col, name + " needs P (the output number)");
    const int index = whole_word('p', kLargestIoIndex, name + " P (the output number)");
    out_.emit(OutputBit{index, code == 620 || code == 640, code <= 630});
    return;
  }
  if (code == 670 || code == 680) {
    if (!b_->has('e')) fail(col, name + " needs E (the output number)");
    if (!b_->has('q')) fail(col, name + " needs Q (the output value)");
    const int index = whole_word('e', kLargestIoIndex, name + " E (the output number)");
    out_.emit(OutputValue{index, b_->value('q'), code == 670});
    return;
  }
  // M66: wait on an input. Standalone rs274 reads every input as 0 at once
  // and makes no call; so does truecut.
  const bool digital = b_->has('p'), analog = b_->has('e');
  if (digital && analog) fail(col, "M66 with both P (digital input) and E (analog input)");
  if (!digital && !analog) fail(col, "M66 needs P (digital input) or E (analog input)");
  if (digital) whole_word('p', kLargestIoIndex, "M66 P (the input number)");
  if (analog) whole_word('e', kLargestIoIndex, "M66 E (the input number)");
  const int mode = b_->has('l') ? whole_word('l', kLargestWaitMode, "M66 L (the wait mode)") : 0;
  if (mode != 0) {
    if (analog) fail(column_of('l'), "M66 E (analog input) only with L0 (immediate)");
    if (!b_->has('q') || b_->value('q') <= 0)
      fail(b_->has('q') ? column_of('q') : column_of('l'),
           "M66 L" + std::to_string(mode) + " needs a timeout Q > 0 (seconds)");
  }
  params_.set(kInputValue, 0);
}

void BlockExecutor::spindle_orient() {
  const double angle = b_->has('r') ? b_->value('r') : 0;
  if (angle < 0 || angle > 360) fail(column_of('r'), "M19 R (the angle) must be within 0..360");
  const int direction = b_->has('p') ? whole_word('p', 2, "M19 P (the direction)") : 0;
  s_.spindle = 0;
  // rs274 makes the call only when R or P is given; M19 alone (or with Q
  // only) stops the spindle without a call.
  if (b_->has('r') || b_->has('p')) {
    OrientSpindle o;
    o.degrees = angle;
    o.m19_direction = direction;
    out_.emit(o);
  }
  if (b_->has('q')) {
    if (b_->value('q') < 0) fail(column_of('q'), "M19 Q (the timeout) must not be negative");
    out_.emit(WaitOrientComplete{b_->value('q')});
  }
}

void BlockExecutor::override_codes() {
  const int code = codes_.m[kOverrideGroup];
  if (code < 0) return;
  const std::string name = "M" + std::to_string(code / 10);
  // M50-M53: P0 switches off, no P or P1 on (rs274 takes any other P as on;
  // truecut refuses it).
  bool on = true;
  if (code >= 500 && b_->has('p')) on = whole_word('p', 1, name + " P (0 off, 1 on)") == 1;
  if (code == 480 || code == 490) {
    on = code == 480;
    s_.feed_override = on;
    out_.emit(FeedOverride{on});
    out_.emit(SpeedOverride{on});
  } else if (code == 500) {
    s_.feed_override = on;
    out_.emit(FeedOverride{on});
  } else if (code == 510) {
    out_.emit(SpeedOverride{on});
  } else if (code == 520) {
    out_.emit(AdaptiveFeed{on});
  } else if (code == 530) {
    out_.emit(FeedHold{on});
  }
}

}  // namespace truecut::interp
