// Near-net stock of a solid of revolution about +Z as a union of
// axis-aligned boxes (the stock format of PartMetadata).
#pragma once

#include <vector>

#include "truecut/sim/benchmark_parts.hpp"

namespace truecut::sim::parts {

// Boxes over z ∈ [z0_mm, z1_mm] whose union covers the disc of radius
// rho_in_mm and whose corners all lie within rho_out_mm of the axis
// (rho_out_mm > rho_in_mm): centred rectangles [−a, a] × [−b, b] with their
// outer corners on the circle rho_out, stepped so that every inner corner of
// the staircase stays outside rho_in.
void add_disc_boxes(std::vector<StockBox>& out, double rho_in_mm, double rho_out_mm, double z0_mm,
                    double z1_mm);

// Boxes covering a sphere of radius r_in_mm (centre on the axis at
// z_centre_mm, upper half only: z ≥ z_centre_mm) with every corner within
// r_out_mm of the centre: slices whose heights keep ρ_out² − ρ_in² at half of
// r_out² − r_in².
void add_dome_boxes(std::vector<StockBox>& out, double r_in_mm, double r_out_mm,
                    double z_centre_mm);

}  // namespace truecut::sim::parts
