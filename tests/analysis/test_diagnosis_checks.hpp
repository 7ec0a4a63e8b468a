// Running a trace diagnosis and reading its explanations, shared by the
// trace-mode diagnosis tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "test_diagnosis_fixtures.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;

// The believed model of the X/Y cases: a known servo loop on X and Y.
inline MachineDescription believed_with_servo() {
  MachineDescription d = xy_machine();
  enable_servo_lag(d.machine, kX, 40.0, 0.9);
  enable_servo_lag(d.machine, kY, 35.0, 0.8);
  return d;
}

// Diagnoses REC against BELIEVED; TRUECUT_DIAGNOSIS_VERBOSE=1 prints the
// progress and the summary.
inline diagnosis::DiagnosisResult run(const MachineDescription& believed, const Recording& rec) {
  diagnosis::DiagnosisOptions o;
  const bool verbose = std::getenv("TRUECUT_DIAGNOSIS_VERBOSE") != nullptr;
  if (verbose) o.progress = [](const std::string& s) { std::printf("  %s\n", s.c_str()); };
  auto r = diagnosis::diagnose(rec, nullptr, believed, o);
  if (verbose) std::printf("%s\n", diagnosis::diagnosis_summary(r).c_str());
  return r;
}

inline const diagnosis::Explanation* find(const diagnosis::DiagnosisResult& r,
                                          const std::string& effect, const std::string& axis) {
  for (const auto& e : r.explanations)
    if (e.effect == effect && e.axis == axis) return &e;
  return nullptr;
}

inline const diagnosis::Parameter* param(const diagnosis::Explanation& e, const std::string& name) {
  for (const auto& p : e.parameters)
    if (p.name == name) return &p;
  return nullptr;
}

// The fitted parameter NAME of E has a 95 % interval covering TRUTH.
inline void expect_covers(const diagnosis::Explanation& e, const std::string& name, double truth,
                          const diagnosis::DiagnosisResult& r) {
  const auto* p = param(e, name);
  ASSERT_NE(p, nullptr) << name << "\n" << diagnosis::diagnosis_summary(r);
  EXPECT_LE(p->ci95_lo, truth) << name << "\n" << diagnosis::diagnosis_summary(r);
  EXPECT_GE(p->ci95_hi, truth) << name << "\n" << diagnosis::diagnosis_summary(r);
}

}  // namespace truecut::analysis::test
