// pos_loop: a joint position loop, built as a shared library that
// `loadrt pos_loop [count=N | names=a,b]` opens at run time.
//
// Model per servo cycle (dt = period): a proportional position loop on the
// encoder reading with velocity feed-forward,
//     v_cmd = ff1 * d(pos-cmd)/dt + kv * (pos-cmd - pos-fb)
// a first-order velocity loop with time constant tau-vel (s) and an
// acceleration limit max-accel (mm/s^2), integrated exactly over the cycle,
// and an encoder that quantises the position to encoder-resolution (mm).
// Steady-state following error at constant speed v with ff1 = 0 is v / kv.
//
// Pins (all float): in pos-cmd, kv (1/s), ff1, tau-vel (s), max-accel,
// encoder-resolution; out pos-fb (encoder), pos-true (unquantised),
// vel-fb (mm/s), f-error (pos-cmd minus the encoder reading the loop used
// this cycle, read at the start of the cycle as a drive would). Function
// <inst>.update.
// The first cycle takes pos-cmd as the position (the axis starts in place).
#include <algorithm>
#include <cmath>

#include "truecut/rt/component_support.hpp"

namespace {

struct PosLoop {
  double* pos_cmd;
  double* kv;
  double* ff1;
  double* tau_vel;
  double* max_accel;
  double* encoder_resolution;
  double* pos_fb;
  double* pos_true;
  double* vel_fb;
  double* f_error;
  double pos;
  double vel;
  double prev_cmd;
  bool started;
};

void update(void* arg, long period_ns) {
  auto& s = *static_cast<PosLoop*>(arg);
  const double dt = double(period_ns) * 1e-9;
  const double cmd = *s.pos_cmd;
  if (!s.started) {
    s.pos = s.prev_cmd = cmd;
    s.vel = 0.0;
    s.started = true;
  }
  const double res = *s.encoder_resolution;
  const double fb_before = res > 0.0 ? std::round(s.pos / res) * res : s.pos;
  const double v_cmd = *s.ff1 * (cmd - s.prev_cmd) / dt + *s.kv * (cmd - fb_before);
  const double tau = std::max(*s.tau_vel, 1e-9);
  double dv = (v_cmd - s.vel) * (1.0 - std::exp(-dt / tau));
  const double dv_max = std::abs(*s.max_accel) * dt;
  dv = std::clamp(dv, -dv_max, dv_max);
  const double v_new = s.vel + dv;
  s.pos += 0.5 * (s.vel + v_new) * dt;
  s.vel = v_new;
  s.prev_cmd = cmd;
  const double fb = res > 0.0 ? std::round(s.pos / res) * res : s.pos;
  *s.pos_fb = fb;
  *s.pos_true = s.pos;
  *s.vel_fb = s.vel;
  *s.f_error = cmd - fb_before;  // the error the loop acted on this cycle
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void**) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto names = instance_names(args, "pos_loop");
    args.expect_consumed("pos_loop");
    for (const auto& n : names) {
      int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      auto* s = b.alloc<PosLoop>();
      b.pin(n + ".pos-cmd", TC_HAL_FLOAT, TC_HAL_IN, &s->pos_cmd);
      b.pin(n + ".kv", TC_HAL_FLOAT, TC_HAL_IN, &s->kv);
      b.pin(n + ".ff1", TC_HAL_FLOAT, TC_HAL_IN, &s->ff1);
      b.pin(n + ".tau-vel", TC_HAL_FLOAT, TC_HAL_IN, &s->tau_vel);
      b.pin(n + ".max-accel", TC_HAL_FLOAT, TC_HAL_IN, &s->max_accel);
      b.pin(n + ".encoder-resolution", TC_HAL_FLOAT, TC_HAL_IN, &s->encoder_resolution);
      b.pin(n + ".pos-fb", TC_HAL_FLOAT, TC_HAL_OUT, &s->pos_fb);
      b.pin(n + ".pos-true", TC_HAL_FLOAT, TC_HAL_OUT, &s->pos_true);
      b.pin(n + ".vel-fb", TC_HAL_FLOAT, TC_HAL_OUT, &s->vel_fb);
      b.pin(n + ".f-error", TC_HAL_FLOAT, TC_HAL_OUT, &s->f_error);
      *s->kv = 40.0;
      *s->tau_vel = 0.002;
      *s->max_accel = 5000.0;
      *s->encoder_resolution = 0.0001;
      b.funct(n + ".update", update, s);
      api->component_ready(hal, id);
    }
    return 0;
  });
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t*, tc_hal_t*, void*) {}
