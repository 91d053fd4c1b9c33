// Each object's points against its model (worker/src/city/model_fit.h): known answers on two
// houses side by side, and the points file a fit job publishes.

#include "city/model_fit.h"

#include <gtest/gtest.h>

#include <cmath>

#include "csgtile/kernel/primitives.h"

namespace csgtile::worker::city::detail {
namespace {

using kernel::Vec3;

kernel::Shape box_at(double x, double dx, double dy, double dz) {
  auto b = kernel::make_box(dx, dy, dz);
  EXPECT_TRUE(b.ok());
  return b.value().moved(kernel::Location::translation(Vec3(x, 0, 0)));
}

// House A: 4 × 4 × 3 at the origin; house B: 4 × 4 × 6 beside it (x from 4 to 8).
TEST(ModelFit, EachPointCountsForTheNearestModelItStandsOver) {
  const kernel::Shape a = box_at(0, 4, 4, 3), b = box_at(4, 4, 4, 6);
  const std::vector<const kernel::Shape*> shapes{&a, &b, nullptr};
  const std::vector<double> sigma{0.06, 0.0, 0.05};
  const std::vector<Vec3> points{
      {1, 1, 3.1},         {2, 2, 3.1}, {3, 1, 3.1},  // 0.1 over A's roof
      {2, 2, 2.8},                                    // 0.2 under it (a point inside counts too)
      {6, 2, 6.3},                                    // 0.3 over B's roof
      {4, 2, 3.05},   // over both (their shared wall): on B's wall, 0.05 from A's eave
      {10, 10, 0.0},  // over neither
      {std::nan(""), 0, 0}};
  long long over_none = -1;
  const auto fits = measure_model_fit(shapes, sigma, points, 0.01, over_none);
  ASSERT_EQ(fits.size(), 3u);
  ASSERT_TRUE(fits[0]);
  EXPECT_EQ(fits[0]->points, 4);
  EXPECT_NEAR(fits[0]->rmse, std::sqrt((3 * 0.01 + 0.04) / 4), 1e-12);
  ASSERT_TRUE(fits[0]->within_2sigma);
  EXPECT_DOUBLE_EQ(*fits[0]->within_2sigma, 0.75);  // 2σ = 0.12: the three over the roof
  EXPECT_DOUBLE_EQ(*fits[0]->sigma, 0.06);
  ASSERT_TRUE(fits[1]);
  EXPECT_EQ(fits[1]->points, 2);
  EXPECT_NEAR(fits[1]->rmse, std::sqrt(0.09 / 2), 1e-12);
  EXPECT_FALSE(fits[1]->within_2sigma);  // no σ known
  EXPECT_FALSE(fits[2]);                 // no shape
  EXPECT_EQ(over_none, 1);               // the NaN point is not counted at all

  // Its record keeps it; read back the same.
  for (const auto& f : fits) {
    ordered_json entry;
    entry["model_fit"] = model_fit_json(f);
    std::optional<ModelFit> back;
    ASSERT_TRUE(read_model_fit(entry, back).ok());
    ASSERT_EQ(back.has_value(), f.has_value());
    if (!f) continue;
    EXPECT_EQ(back->points, f->points);
    EXPECT_EQ(back->rmse, f->rmse);
    EXPECT_EQ(back->within_2sigma, f->within_2sigma);
  }
  ordered_json bad;
  bad["model_fit"] = {{"points", "many"}};
  std::optional<ModelFit> back;
  EXPECT_EQ(read_model_fit(bad, back).code, ErrorCode::Internal);
}

TEST(ModelFit, ThePointsFileComesBackAndAShortOneFailsByName) {
  const std::vector<Vec3> points{{0.5, -1.25, 3.0}, {1024.5, 2048.25, -7.75}};
  const std::string bytes = encode_points(points);
  EXPECT_EQ(bytes.size(), 8u + 8u + 2u * 12u);
  std::vector<Vec3> back;
  ASSERT_TRUE(decode_points(bytes, "p.pts", back).ok());
  EXPECT_EQ(back, points);  // exact in float32
  const Failure short_one = decode_points(bytes.substr(0, bytes.size() - 1), "p.pts", back);
  EXPECT_EQ(short_one.code, ErrorCode::InputInvalid);
  EXPECT_NE(short_one.message.find("p.pts"), std::string::npos) << short_one.message;
  EXPECT_TRUE(back.empty());
  EXPECT_EQ(decode_points("LASF and more bytes", "q.pts", back).code, ErrorCode::InputInvalid);
  ASSERT_TRUE(decode_points(encode_points({}), "empty.pts", back).ok());
  EXPECT_TRUE(back.empty());
}

}  // namespace
}  // namespace csgtile::worker::city::detail
