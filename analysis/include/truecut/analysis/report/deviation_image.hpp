// Pictures for the reports: a triangle mesh rendered orthographically with
// each vertex coloured by a scalar (a deviation), shaded by the light on the
// surface, encoded as PNG. Pure software: a z-buffer rasteriser, no GPU,
// deterministic bytes for the same input.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "truecut/offline/mesh.hpp"

namespace truecut::analysis::report {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel, top row first
};

// A diverging colour scale: -limit blue, 0 white-green, +limit red; values
// beyond the limit saturate. NaN (no value) is grey.
std::array<std::uint8_t, 3> deviation_colour(double value, double limit);

struct MeshView {
  Eigen::Vector3d view_direction{-1.0, -1.2, -1.0};  // from the eye toward the part
  Eigen::Vector3d up{0.0, 0.0, 1.0};
  int width_px = 480;
  int height_px = 360;
};

// Renders the mesh as seen along view.view_direction, fitted to the image
// around the vertices that carry a value (all vertices when none does).
// vertex_values: one per vertex (NaN = no value, drawn grey); triangles with
// any NaN vertex are drawn grey. colour_limit is the value that saturates
// the colour scale.
RgbImage render_mesh(const offline::TriangleMesh& mesh, const std::vector<double>& vertex_values,
                     double colour_limit, const MeshView& view = {});

// PNG bytes of the image (libpng).
std::string encode_png(const RgbImage& image);

// RFC 4648 base64, for data: URLs in self-contained HTML.
std::string base64(const std::string& bytes);

}  // namespace truecut::analysis::report
