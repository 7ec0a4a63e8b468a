// The files `truecut run MACHINE PROGRAM` (run_soft_cnc) writes into its
// output folder, by the component or step that writes each. Commands that
// read a run's folder, or keep other outputs off these names, take them
// from here.
#pragma once

#include <array>

namespace truecut::sim {

inline constexpr const char* kMachinedStl = "machined.stl";  // the cutting component, at unload
inline constexpr const char* kMachinedPly = "machined.ply";  // the same surface as PLY
inline constexpr const char* kTraceCsv = "trace.csv";        // the recorder (sim/hal/soft_cnc.hal)
inline constexpr const char* kSoftCncHal = "soft_cnc.hal";   // the wiring, copied for the record
inline constexpr const char* kRunIni = "run.ini";            // the job's INI the wiring reads
inline constexpr const char* kFieldCopy = "field.tcf";       // the field, when it is swapped

inline constexpr std::array<const char*, 6> kSoftCncOutputs = {
    kMachinedStl, kMachinedPly, kTraceCsv, kSoftCncHal, kRunIni, kFieldCopy};

}  // namespace truecut::sim
