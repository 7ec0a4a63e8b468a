// The full sweep of the independent planted cases (planted_cases.hpp):
// every effect at three magnitudes over N seeds (default 20), a table per
// effect and magnitude of the seeds passed and the worst relative error.
// Not part of ctest (it takes minutes); run by hand:
//   analysis_planted_sweep [SEEDS] [EFFECT-NAME] [-v] [-m MAGNITUDE-INDEX] [-s FIRST-SEED] [-a]
//                          [-n NOISE-UM]
// (-m 0|1|2: one magnitude only; -s: seeds FIRST-SEED … FIRST-SEED + SEEDS − 1;
// -a: antithetic, every seed's noise with the opposite sign — the mean of a
// seed's two estimates cancels the noise to first order and leaves the
// estimator's bias; -n: σ of the measurement noise in µm instead of 1, a
// small σ shows a case's bias directly; TRUECUT_DIAGNOSIS_VERBOSE=1 prints
// the diagnosis' progress lines).
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "planted_cases.hpp"

using namespace truecut::test::planted;

int main(int argc, char** argv) {
  int seeds = 20;
  std::string only;
  bool verbose = false, antithetic = false;
  int only_magnitude = -1, first_seed = 1;
  double noise_um = -1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-v") == 0)
      verbose = true;
    else if (std::strcmp(argv[i], "-a") == 0)
      antithetic = true;
    else if (std::strcmp(argv[i], "-m") == 0 && i + 1 < argc)
      only_magnitude = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "-n") == 0 && i + 1 < argc)
      noise_um = std::atof(argv[++i]);
    else if (std::strcmp(argv[i], "-s") == 0 && i + 1 < argc)
      first_seed = std::atoi(argv[++i]);
    else if (std::isdigit(static_cast<unsigned char>(argv[i][0])))
      seeds = std::atoi(argv[i]);
    else
      only = argv[i];
  }
  // One directory per process: a case's file name does not change with -n,
  // and sweeps run side by side (other worktrees' among them) must not
  // read each other's half-written recordings.
  const auto dir = std::filesystem::temp_directory_path() /
                   ("truecut_planted_sweep_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  int failed_total = 0;
  std::printf("| effect | magnitude | seeds passed | worst error | first failure |\n");
  std::printf("|---|---|---|---|---|\n");
  for (Effect e : kSweepEffects) {
    if (!only.empty() && only != effect_name(e)) continue;
    for (int m = 0; m < 3; ++m) {
      if (only_magnitude >= 0 && m != only_magnitude) continue;
      int passed = 0;
      double worst = 0;
      std::string first_failure;
      for (int s = first_seed; s < first_seed + seeds; ++s) {
        Case c = sweep_case(e, m, unsigned(s));
        if (noise_um >= 0) c.spec.noise_mm = noise_um * 1e-3;
        if (antithetic) c.spec.noise_mm = -c.spec.noise_mm, c.name += "_antithetic";
        const auto t0 = std::chrono::steady_clock::now();
        const auto r = diagnose_case(c, dir);
        const Verdict v = judge(c, r);
        std::filesystem::remove(dir / (c.name + ".csv"));
        worst = std::max(worst, v.worst_rel_error);
        if (v.pass)
          ++passed;
        else if (first_failure.empty())
          first_failure = "seed " + std::to_string(s) + ": " + v.why;
        if (verbose) {
          const double sec =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          std::fprintf(stderr, "%s %s (%.1f s) %s\n%s\n", c.name.c_str(), v.pass ? "pass" : "FAIL",
                       sec, v.why.c_str(),
                       truecut::analysis::diagnosis::diagnosis_summary(r).c_str());
        }
      }
      failed_total += seeds - passed;
      std::printf("| %s | %g | %d/%d | %.1f %% | %s |\n", effect_name(e), sweep_magnitude(e, m),
                  passed, seeds, 100 * worst, first_failure.c_str());
      std::fflush(stdout);
    }
  }
  std::filesystem::remove_all(dir);
  return failed_total == 0 ? 0 : 1;
}
