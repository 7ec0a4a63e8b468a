// Trace mode, tool-centre point: the measured TCP (tcp_true_x/y/z) against
// the believed kinematics applied to the recorded joints. Joint traces alone
// cannot see where the rotary axis lines are or how long the tool is; the
// TCP can. Candidates: the rotary_location parameters (A and C axis-line
// offsets, tilts, zero offsets) and tool_length_error, one signature column
// each (∂TCP/∂parameter by central differences of the kinematics), selected
// one parameter at a time by BIC, fitted by Gauss–Newton, with intervals
// and the not-identifiable pairs (docs/diagnosis.md, "Tool-centre point").
#pragma once

#include <string>
#include <vector>

#include "trace.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

struct TcpStage {
  TcpComparison comparison;
  std::vector<Mismatch> mismatch;  // components above 1.5 × their floor (fitted block)
  std::vector<Explanation> explanations;
  std::vector<NotIdentifiable> not_identifiable;
  std::vector<std::string> tested;
  sim::MachineParams fitted;  // `base` with the selected parameters at their fitted values
};

// `train` / `heldout_rows`: the samples of each block of `trace`; with a
// hold-out recording (`holdout`, not null) all its samples are held out
// instead. Offsets and weights come from the fitted block.
TcpStage fit_tcp(const Trace& trace, const std::vector<char>& train,
                 const std::vector<char>& heldout_rows, const Trace* holdout,
                 const sim::MachineParams& base, const DiagnosisOptions& options);

}  // namespace truecut::analysis::diagnosis
