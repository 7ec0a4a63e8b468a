// siggen: LinuxCNC's signal generator. Per instance: out pins sine, cosine,
// triangle, sawtooth, square (float) and clock (bit); in pins frequency (Hz),
// amplitude, offset, reset; function <inst>.update.
#include <cmath>
#include <numbers>

#include "builtin_components.hpp"
#include "truecut/rt/component_support.hpp"

namespace truecut::rt::hal::builtin {
namespace {

struct Siggen {
  double* sine;
  double* cosine;
  double* triangle;
  double* sawtooth;
  double* square;
  bool* clock;
  double* frequency;
  double* amplitude;
  double* offset;
  bool* reset;
  double index;  // phase in [0, 1)
};

// The cycles of one period. The period in seconds first: frequency ×
// period_ns overflowed for a frequency of 1e308 Hz, and the phase became
// inf − inf = NaN in every output. An advance that is not finite does not
// move the phase.
double phase_step(double frequency_hz, long period_ns) {
  const double cycles = frequency_hz * (double(period_ns) * 1e-9);
  return std::isfinite(cycles) ? cycles : 0.0;
}

void update(void* arg, long period_ns) {
  auto& s = *static_cast<Siggen*>(arg);
  if (*s.reset) {
    s.index = 0.0;
  } else {
    s.index += phase_step(*s.frequency, period_ns);
    s.index -= std::floor(s.index);
  }
  const double a = *s.amplitude, o = *s.offset, i = s.index;
  const double w = 2.0 * std::numbers::pi * i;
  *s.sine = a * std::sin(w) + o;
  *s.cosine = a * std::cos(w) + o;
  *s.sawtooth = a * (2.0 * i - 1.0) + o;
  *s.triangle = a * (i < 0.5 ? 4.0 * i - 1.0 : 3.0 - 4.0 * i) + o;
  *s.square = (i < 0.5 ? a : -a) + o;
  *s.clock = i < 0.5;
}

}  // namespace

int siggen_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc, const char* const* argv, void**) {
  using namespace component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto names = instance_names(args, "siggen");
    args.expect_consumed("siggen");
    for (const auto& n : names) {
      int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      auto* s = b.alloc<Siggen>();
      b.pin(n + ".sine", TC_HAL_FLOAT, TC_HAL_OUT, &s->sine);
      b.pin(n + ".cosine", TC_HAL_FLOAT, TC_HAL_OUT, &s->cosine);
      b.pin(n + ".triangle", TC_HAL_FLOAT, TC_HAL_OUT, &s->triangle);
      b.pin(n + ".sawtooth", TC_HAL_FLOAT, TC_HAL_OUT, &s->sawtooth);
      b.pin(n + ".square", TC_HAL_FLOAT, TC_HAL_OUT, &s->square);
      b.pin(n + ".clock", TC_HAL_BIT, TC_HAL_OUT, &s->clock);
      b.pin(n + ".frequency", TC_HAL_FLOAT, TC_HAL_IN, &s->frequency);
      b.pin(n + ".amplitude", TC_HAL_FLOAT, TC_HAL_IN, &s->amplitude);
      b.pin(n + ".offset", TC_HAL_FLOAT, TC_HAL_IN, &s->offset);
      b.pin(n + ".reset", TC_HAL_BIT, TC_HAL_IN, &s->reset);
      *s->frequency = 1.0;
      *s->amplitude = 1.0;
      *s->cosine = 1.0;
      b.funct(n + ".update", update, s);
      api->component_ready(hal, id);
    }
    return 0;
  });
}

void siggen_exit(const tc_hal_api_t*, tc_hal_t*, void*) {}

}  // namespace truecut::rt::hal::builtin
