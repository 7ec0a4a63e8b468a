// The report pictures: colour scale, rasteriser, PNG container, base64.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "truecut/analysis/report/deviation_image.hpp"
#include "truecut/analysis/report/svg_plots.hpp"

namespace truecut::analysis::report {
namespace {

offline::TriangleMesh unit_square_facing(const Eigen::Vector3d& normal) {
  // Two triangles of a 10 mm square in the plane through the origin.
  Eigen::Vector3d a = normal.unitOrthogonal(), b = normal.cross(a);
  offline::TriangleMesh m;
  m.vertices_mm = {-5 * a - 5 * b, 5 * a - 5 * b, 5 * a + 5 * b, -5 * a + 5 * b};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(ReportColour, ScaleEndsAndSaturation) {
  EXPECT_EQ(deviation_colour(1.0, 1.0), deviation_colour(5.0, 1.0));
  EXPECT_EQ(deviation_colour(-1.0, 1.0), deviation_colour(-3.0, 1.0));
  const auto red = deviation_colour(1.0, 1.0), blue = deviation_colour(-1.0, 1.0);
  EXPECT_GT(red[0], red[2]);
  EXPECT_GT(blue[2], blue[0]);
  const auto grey = deviation_colour(std::numeric_limits<double>::quiet_NaN(), 1.0);
  EXPECT_EQ(grey[0], grey[1]);
  EXPECT_EQ(grey[1], grey[2]);
}

TEST(ReportRender, FrontFaceIsColouredBackFaceIsCulled) {
  MeshView view;
  view.view_direction = {0, 0, -1};  // looking down
  view.up = {0, 1, 0};
  view.width_px = 64;
  view.height_px = 64;
  const auto up_facing = unit_square_facing({0, 0, 1});
  const RgbImage img = render_mesh(up_facing, {1.0, 1.0, 1.0, 1.0}, 1.0, view);
  ASSERT_EQ(64 * 64 * 3u, img.rgb.size());
  const size_t centre = (32 * 64 + 32) * 3;
  EXPECT_GT(img.rgb[centre], img.rgb[centre + 2]);  // red: +limit
  const auto down_facing = unit_square_facing({0, 0, -1});
  const RgbImage back = render_mesh(down_facing, {1.0, 1.0, 1.0, 1.0}, 1.0, view);
  EXPECT_EQ(255, back.rgb[centre]);  // culled: background
  EXPECT_EQ(255, back.rgb[centre + 1]);
}

TEST(ReportRender, Deterministic) {
  const auto m = unit_square_facing(Eigen::Vector3d(1, 2, 3).normalized());
  const std::vector<double> v{0.1, -0.2, 0.3, 0.0};
  EXPECT_EQ(encode_png(render_mesh(m, v, 0.3)), encode_png(render_mesh(m, v, 0.3)));
}

TEST(ReportPng, SignatureAndHeader) {
  RgbImage img;
  img.width = 7;
  img.height = 5;
  img.rgb.assign(7 * 5 * 3, 128);
  const std::string png = encode_png(img);
  ASSERT_GT(png.size(), 33u);
  EXPECT_EQ(std::string("\x89PNG\r\n\x1a\n", 8), png.substr(0, 8));
  EXPECT_EQ("IHDR", png.substr(12, 4));
  EXPECT_EQ(7, (unsigned char)png[19]);  // width, big endian
  EXPECT_EQ(5, (unsigned char)png[23]);  // height
}

TEST(ReportBase64, Rfc4648Vectors) {
  EXPECT_EQ("", base64(""));
  EXPECT_EQ("Zg==", base64("f"));
  EXPECT_EQ("Zm8=", base64("fo"));
  EXPECT_EQ("Zm9v", base64("foo"));
  EXPECT_EQ("Zm9vYg==", base64("foob"));
  EXPECT_EQ("Zm9vYmE=", base64("fooba"));
  EXPECT_EQ("Zm9vYmFy", base64("foobar"));
}

TEST(ReportSvg, HistogramCountsEveryValueOnce) {
  // Two values in one bin, one beyond the range (clamped into the last bin):
  // the step heights are 66.7 % and 33.3 %.
  const std::string svg = histogram_svg({{"a", "#f00", {0.1, 0.1, 99.0}}}, 1.0, 4, 0.5, "um");
  EXPECT_NE(std::string::npos, svg.find("<svg"));
  EXPECT_NE(std::string::npos, svg.find("stroke-dasharray"));  // tolerance lines
  EXPECT_EQ(std::string::npos, svg.find("nan"));
  EXPECT_EQ("a&lt;b&amp;", html_escape("a<b&"));
}

}  // namespace
}  // namespace truecut::analysis::report
