// The field fit with the tool's rotation (FieldPipelineOptions::tool_rotation):
// the rotation estimated per tool-path sample (tool_rotation.hpp), fitted as
// a second field on the same grid, and joined with the translation into one
// CorrectionField with rotation channels.
#pragma once

#include "truecut/offline/field_pipeline.hpp"

namespace truecut::offline {

// Replaces r.tool_samples' vectors by the translation at the tip, fits both
// fields and returns the joined one (the translation fit's weights and
// statistics). Throws std::logic_error if the two grids differ (they
// cannot: the same sample positions).
FieldFitResult fit_with_tool_rotation(FieldPipelineResult& r, const FieldPipelineInputs& in,
                                      const FieldPipelineOptions& opt);

}  // namespace truecut::offline
