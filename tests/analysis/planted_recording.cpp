// The independent planted-recording generator (planted_recording.hpp).
#include "planted_recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <stdexcept>

namespace truecut::test::planted {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One axis stepping through a list of stops with cycloidal moves
// s(u) = d·(u − sin(2πu)/2π), u = τ/D: zero velocity and acceleration at
// both ends, peak speed 2d/D, peak acceleration 2πd/D².
class Stepper {
 public:
  Stepper(double start, double vmax, double amax) : start_(start), vmax_(vmax), amax_(amax) {}
  void move(double to, double dwell_after) {
    const double from = legs_.empty() ? start_ : legs_.back().to;
    const double d = std::abs(to - from);
    const double D = std::max({2 * d / vmax_, std::sqrt(2 * kPi * d / amax_), 1e-3});
    legs_.push_back({from, to, D, dwell_after});
  }
  void dwell(double s) {
    if (legs_.empty())
      first_dwell_ += s;
    else
      legs_.back().dwell += s;
  }
  double at(double t) const {
    t -= first_dwell_;
    if (t <= 0) return start_;
    for (const auto& l : legs_) {
      if (t < l.D) {
        const double u = t / l.D;
        return l.from + (l.to - l.from) * (u - std::sin(2 * kPi * u) / (2 * kPi));
      }
      t -= l.D;
      if (t < l.dwell) return l.to;
      t -= l.dwell;
    }
    return legs_.empty() ? start_ : legs_.back().to;
  }
  double duration() const {
    double s = first_dwell_;
    for (const auto& l : legs_)
      s += l.D + l.dwell;
    return s;
  }

 private:
  struct Leg {
    double from, to, D, dwell;
  };
  double start_, vmax_, amax_;
  double first_dwell_ = 0.0;
  std::vector<Leg> legs_;
};

// ISO 230-2 linear test of X: five targets, 2 mm over-travel beyond both
// ends, a dwell at every target, two bidirectional cycles.
const Stepper& iso_stepper(int cycles) {
  auto make = [](int cycles) {
    const double targets[] = {0.0, 9.3, 20.1, 29.6, 40.0};
    const double over = 2.0, dwell = 0.25, turn = 0.05;
    Stepper st(targets[0] - over, 30.0, 600.0);
    st.dwell(0.4);
    for (int cycle = 0; cycle < cycles; ++cycle) {
      for (double p : targets)
        st.move(p, dwell);
      st.move(targets[4] + over, turn);
      for (int i = 4; i >= 0; --i)
        st.move(targets[i], dwell);
      st.move(targets[0] - over, turn);
    }
    st.dwell(0.3);
    return st;
  };
  static const Stepper one = make(1), two = make(2);
  return cycles == 1 ? one : two;
}

// Circles in XY (centre (30, 20), R 20 mm unless the spec says otherwise,
// 40 mm/s): 1.5 turns counter-clockwise from the bottom, a stop, 1.5 turns
// clockwise back. The angular speed ramps in and out as (1 − cos)/2 over
// 0.6 s.
struct Circle {
  double cx = 30, cy = 20, R = 20, omega = 2.0, ramp = 0.6, turn_angle = 3 * kPi;
  double lead = 0.3, pause = 0.4, tail = 0.4;
  double cruise() const { return (turn_angle - omega * ramp) / omega; }
  double leg() const { return 2 * ramp + cruise(); }
  // Angle covered after time tau into one leg.
  double swept(double tau) const {
    if (tau <= 0) return 0;
    if (tau < ramp) return omega * (tau / 2 - ramp / (2 * kPi) * std::sin(kPi * tau / ramp));
    const double a_up = omega * ramp / 2;
    if (tau < ramp + cruise()) return a_up + omega * (tau - ramp);
    const double u = std::min(tau - ramp - cruise(), ramp);
    return a_up + omega * cruise() + omega * (u / 2 + ramp / (2 * kPi) * std::sin(kPi * u / ramp));
  }
  double angle(double t) const {
    const double th0 = -kPi / 2;
    if (t < lead) return th0;
    t -= lead;
    if (t < leg() + pause) return th0 + swept(t);
    t -= leg() + pause;
    return th0 + turn_angle - swept(t);
  }
  double duration() const { return lead + 2 * leg() + pause + tail; }
};

// Time warped to start and end at standstill: ds/dt ramps (1 − cos)/2 over
// `ramp` seconds at both ends.
struct Warp {
  double lead = 0.3, ramp = 0.8, run = 11.0, tail = 0.3;
  double s(double t) const {
    t -= lead;
    if (t <= 0) return 0;
    auto up = [&](double u) { return u / 2 - ramp / (2 * kPi) * std::sin(kPi * u / ramp); };
    if (t < ramp) return up(t);
    const double s_up = ramp / 2;
    const double flat = run - 2 * ramp;
    if (t < ramp + flat) return s_up + (t - ramp);
    const double u = std::min(t - ramp - flat, ramp);
    return s_up + flat + (u / 2 + ramp / (2 * kPi) * std::sin(kPi * u / ramp));
  }
  double duration() const { return lead + run + tail; }
};

double sign(double v) {
  return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
}

// The servo of one axis: P position loop with velocity feed-forward,
// sampled every T; PI velocity loop on the mass with Coulomb friction
// (Karnopp stick), integrated in 200 sub-steps per period (5 µs at 1 kHz):
// with 20, the explicit steps' own lag was 4 % of the servo error left at
// ff1 0.97 and biased a fitted Kv by that much (docs/diagnosis.md).
struct Servo {
  const Axis& ax;
  double p = 0, v = 0, integ = 0;
  double kp() const { return 2 * kPi * ax.vel_bandwidth_hz; }
  double ki() const { return kp() / ax.vel_integral_time_s; }
  double encoder() const {
    const double q = ax.encoder_resolution;
    return q > 0 ? q * std::round(p / q) : p;
  }
  // Advances one period T with the velocity set-point held.
  void period(double v_ref, double T, const std::function<void(double)>& on_substep) {
    const int n = 200;
    const double h = T / n;
    const double fc = ax.coulomb_n / ax.mass_kg * 1000.0;  // N/kg = m/s² → mm/s²
    for (int i = 0; i < n; ++i) {
      const double e = v_ref - v;
      double a_drv = kp() * e + ki() * (integ + e * h);
      const bool saturated = std::abs(a_drv) > ax.max_accel;
      if (!(saturated && sign(a_drv) == sign(e))) integ += e * h;
      a_drv = std::clamp(kp() * e + ki() * integ, -ax.max_accel, ax.max_accel);
      double a;
      if (v == 0.0)
        a = std::abs(a_drv) <= fc ? 0.0 : a_drv - fc * sign(a_drv);
      else
        a = a_drv - fc * sign(v);
      double v_new = v + a * h;
      if (fc > 0 && v != 0.0 && sign(v_new) != sign(v))
        v_new = 0.0;  // friction stops, never reverses
      // Position exact for the sub-step's constant acceleration: p += h·v_new
      // would lead the true position by h/2·v.
      p += h * 0.5 * (v + v_new);
      v = v_new;
      on_substep(p);
    }
  }
};

Circle circle(const Spec& spec) {
  Circle c;
  c.turn_angle = 2 * kPi * spec.circle_turns;
  c.omega = c.omega * c.R / spec.circle_radius_mm;  // the same feed
  c.R = spec.circle_radius_mm;
  return c;
}

}  // namespace

double duration_s(const Spec& spec) {
  switch (spec.path) {
    case PathKind::kIso230X:
      return iso_stepper(spec.iso_cycles).duration();
    case PathKind::kCircleXY:
      return circle(spec).duration();
    case PathKind::kContour3:
      return Warp{}.duration();
  }
  return 0;
}

std::array<double, 3> command(const Spec& spec, double t) {
  switch (spec.path) {
    case PathKind::kIso230X:
      return {iso_stepper(spec.iso_cycles).at(t), 15.0, -5.0};
    case PathKind::kCircleXY: {
      const Circle c = circle(spec);
      const double th = c.angle(t);
      return {c.cx + c.R * std::cos(th), c.cy + c.R * std::sin(th), -5.0};
    }
    case PathKind::kContour3: {
      const double s = Warp{}.s(t);
      return {25 + 20 * std::sin(2 * kPi * s / 5.3), 15 + 15 * std::sin(2 * kPi * s / 3.7 + 0.9),
              -10 + 8 * std::sin(2 * kPi * s / 4.4 + 2.1)};
    }
  }
  return {};
}

Trace generate(const Plant& plant, const Spec& spec) {
  const double T = spec.period_s;
  const int n = int(std::floor(duration_s(spec) / T)) + 1;
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Trace tr;
  std::array<std::vector<double>, 3> motor, table;
  for (int j = 0; j < 3; ++j)
    motor[j].resize(n), table[j].resize(n), tr.cmd[j].resize(n), tr.act[j].resize(n);
  tr.t.resize(n);
  for (int k = 0; k < n; ++k) {
    tr.t[k] = k * T;
    const auto c = command(spec, k * T);
    for (int j = 0; j < 3; ++j)
      tr.cmd[j][k] = c[j];
  }
  for (int j = 0; j < 3; ++j) {
    const Axis& ax = plant.axes[j];
    const double half = ax.backlash_mm / 2;
    const auto& c = tr.cmd[j];
    // The table starts engaged for the first move (as after homing in that
    // direction): trailing the motor by half the lost motion.
    double first_dir = 0;
    for (int k = 1; k < n && first_dir == 0; ++k)
      first_dir = sign(c[k] - c[0]);
    double q = c[0] - first_dir * half;
    auto drag = [&](double p) { q = std::min(std::max(q, p - half), p + half); };
    if (!ax.servo) {
      for (int k = 0; k < n; ++k) {
        drag(c[k]);
        motor[j][k] = c[k];
        table[j][k] = q;
        tr.act[j][k] = c[k];
      }
      continue;
    }
    Servo s{ax};
    s.p = c[0];
    for (int k = 0; k < n; ++k) {
      motor[j][k] = s.p;
      table[j][k] = q;
      tr.act[j][k] = s.encoder();
      const double v_ref =
          ax.ff1 * (c[k] - c[std::max(k - 1, 0)]) / T + ax.kv_per_s * (c[k] - s.encoder());
      s.period(v_ref, T, drag);
    }
  }
  std::array<std::vector<double>, 3> truepos;
  for (int j = 0; j < 3; ++j) {
    const Axis& ax = plant.axes[j];
    truepos[j].resize(n);
    for (int k = 0; k < n; ++k) {
      const double p = motor[j][k];
      const double pitch =
          ax.pitch_scale_um_per_m * (p - ax.pitch_reference_mm) * 1e-6 +
          ax.pitch_amplitude_um * 1e-3 *
              std::sin(2 * kPi * p / ax.pitch_period_mm + ax.pitch_phase_deg * kPi / 180);
      const double thermal = ax.thermal_gain_mm * (1 - std::exp(-tr.t[k] / ax.thermal_tau_s));
      truepos[j][k] = table[j][k] + pitch + thermal;
    }
  }
  for (int j = 0; j < 3; ++j)
    tr.meas[j].resize(n);
  for (int k = 0; k < n; ++k) {
    const double x = truepos[0][k], y = truepos[1][k], z = truepos[2][k];
    tr.meas[0][k] = x + (plant.xy_urad * y + plant.zx_urad * z) * 1e-6;
    tr.meas[1][k] = y + plant.yz_urad * z * 1e-6;
    tr.meas[2][k] = z;
  }
  // Noise last, in a fixed order, so a case's noise depends on its seed only.
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < 3; ++j) {
      tr.meas[j][k] += spec.noise_mm * gauss(rng);
      tr.act[j][k] += spec.act_noise_mm * gauss(rng);
    }
  return tr;
}

void write_csv(const std::filesystem::path& file, const Trace& tr, const Spec& spec) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  const char* names[] = {"x", "y", "z"};
  out << "t";
  for (int j = 0; j < 3; ++j) {
    if (!spec.record[j]) continue;
    out << ',' << names[j] << "_cmd," << names[j] << "_act";
    if (spec.meas) out << ',' << names[j] << "_meas";
  }
  out << '\n';
  char buf[64];
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%.6f", tr.t[k]);
    out << buf;
    for (int j = 0; j < 3; ++j) {
      if (!spec.record[j]) continue;
      std::snprintf(buf, sizeof buf, ",%.7f,%.7f", tr.cmd[j][k], tr.act[j][k]);
      out << buf;
      if (spec.meas) {
        std::snprintf(buf, sizeof buf, ",%.7f", tr.meas[j][k]);
        out << buf;
      }
    }
    out << '\n';
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

}  // namespace truecut::test::planted
