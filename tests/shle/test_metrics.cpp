#include <gtest/gtest.h>

#include <cmath>

#include "shle/error.h"
#include "shle/metrics.h"

namespace {

TEST(Metrics, HeightErrors) {
  shle::HeightError e = shle::height_error(2.9, 3.0);
  EXPECT_NEAR(e.he, -0.1, 1e-12);
  EXPECT_NEAR(e.her, -0.1 / 3.0, 1e-12);
  EXPECT_NEAR(e.he_abs, 0.1, 1e-12);
  EXPECT_NEAR(e.her_abs, 0.1 / 3.0, 1e-12);
  shle::HeightErrorSummary s = shle::summarize_height_errors({2.9, 3.2, 3.0}, 3.0);
  EXPECT_EQ(s.n, 3u);
  EXPECT_NEAR(s.mean.he, 0.1 / 3.0, 1e-12);
  EXPECT_NEAR(s.mean.he_abs, 0.1, 1e-12);
  EXPECT_EQ(shle::summarize_height_errors({}, 3.0).n, 0u);
  EXPECT_THROW(shle::height_error(2.0, 0.0), shle::Error);
  EXPECT_THROW(shle::height_error(NAN, 3.0), shle::Error);
}

TEST(Metrics, CentrePointDistance) {
  shle::CentreDistance c;
  ASSERT_TRUE(shle::centre_distance(shle::Box{10, 10, 210, 110}, shle::Box{0, 0, 200, 100}, &c));
  EXPECT_NEAR(c.cpd, std::sqrt(200.0), 1e-12);
  EXPECT_NEAR(c.rcpda, std::sqrt(200.0) / 20000.0, 1e-15);
  EXPECT_NEAR(c.rcpdh, std::sqrt(200.0) / std::sqrt(50000.0), 1e-12);
  EXPECT_FALSE(shle::centre_distance(shle::Box{0, 0, 1, 1}, shle::Box{5, 5, 5, 9}, &c));
  EXPECT_FALSE(shle::centre_distance(shle::Box{0, 0, NAN, 1}, shle::Box{0, 0, 9, 9}, &c));
}

}  // namespace
