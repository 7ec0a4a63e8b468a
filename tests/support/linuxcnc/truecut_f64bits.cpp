// Test helper module for LinuxCNC: halsampler prints float pins with "%f"
// (six decimals), too coarse for a bit-for-bit comparison. This module
// copies the bits of float pins to u32 pins, which halsampler prints exactly.
//
//   loadrt truecut_f64bits count=N
//
// Pins truecut_f64bits.K.in (float in), truecut_f64bits.K.hi and .lo (u32
// out: the high and low 32 bits of the IEEE 754 double); function
// truecut_f64bits.update copies all N.
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "hal.h"
#include "rtapi.h"
#include "rtapi_app.h"

MODULE_AUTHOR("truecut");
MODULE_DESCRIPTION("float pins as their bits (test helper)");
MODULE_LICENSE("GPL");

static int count = 1;
RTAPI_MP_INT(count, "number of float pins");

namespace {

struct Channel {
  hal_float_t* in;
  hal_u32_t* hi;
  hal_u32_t* lo;
};

int comp_id = -1;
Channel* channels = nullptr;

void update(void*, long) {
  for (int i = 0; i < count; ++i) {
    const double v = *channels[i].in;
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    *channels[i].hi = static_cast<uint32_t>(bits >> 32);
    *channels[i].lo = static_cast<uint32_t>(bits);
  }
}

}  // namespace

extern "C" int rtapi_app_main(void) {
  if (count < 1 || count > 256) {
    rtapi_print_msg(RTAPI_MSG_ERR, "truecut_f64bits: count=%d must be 1..256\n", count);
    return -EINVAL;
  }
  comp_id = hal_init("truecut_f64bits");
  if (comp_id < 0) return comp_id;
  channels = static_cast<Channel*>(hal_malloc(count * static_cast<long>(sizeof(Channel))));
  if (channels == nullptr) {
    hal_exit(comp_id);
    return -ENOMEM;
  }
  for (int i = 0; i < count; ++i) {
    int r = hal_pin_float_newf(HAL_IN, &channels[i].in, comp_id, "truecut_f64bits.%d.in", i);
    if (r == 0) r = hal_pin_u32_newf(HAL_OUT, &channels[i].hi, comp_id, "truecut_f64bits.%d.hi", i);
    if (r == 0) r = hal_pin_u32_newf(HAL_OUT, &channels[i].lo, comp_id, "truecut_f64bits.%d.lo", i);
    if (r != 0) {
      hal_exit(comp_id);
      return r;
    }
  }
  const int r = hal_export_funct("truecut_f64bits.update", update, nullptr, 1, 0, comp_id);
  if (r != 0) {
    hal_exit(comp_id);
    return r;
  }
  hal_ready(comp_id);
  return 0;
}

extern "C" void rtapi_app_exit(void) {
  hal_exit(comp_id);
}
