// The MIL tracker filling the gaps of a rendered SHLE drive (shle_synth, 1280x720)
// as the released stage 1 does, against cv2.TrackerMIL on the same PNG frames read
// with cv2.imread (tests/reference/shle_mil_ref.py --synth): the same boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "shle/tracker.h"
#include "weights/safetensors.h"

namespace {

template <typename T>
std::vector<T> copy(const weights::SafeTensors& st, const std::string& name) {
  std::vector<T> v(static_cast<std::size_t>(st.info(name).numel()));
  if (!v.empty()) std::memcpy(v.data(), st.raw(name), sizeof(T) * v.size());
  return v;
}

TEST(MilOpenCVSynth, SameBoxesOnARenderedDrive) {
  const weights::SafeTensors st =
      weights::SafeTensors::load(std::string(ROADNN_REF_DIR) + "/shle_mil_synth.safetensors");
  const weights::TensorInfo& info = st.info("frames");
  const int n = static_cast<int>(info.shape.at(0)), h = static_cast<int>(info.shape.at(1)),
            w = static_cast<int>(info.shape.at(2));
  const std::vector<std::uint8_t> px = copy<std::uint8_t>(st, "frames");
  const std::vector<std::int32_t> seeds = copy<std::int32_t>(st, "seeds"), want = copy<std::int32_t>(st, "boxes");
  const std::vector<std::uint8_t> ok = copy<std::uint8_t>(st, "ok");
  ASSERT_EQ(want.size(), static_cast<std::size_t>(n) * 4);
  ASSERT_GE(seeds.size(), 2u);
  auto frame = [&](int i) { return shle::GrayView{w, h, px.data() + static_cast<std::size_t>(i) * w * h}; };
  shle::MilTracker t;  // one process: the seeds continue its rand() stream
  double max_diff = 0;
  int tracked = 0, moved = 0;
  for (std::size_t k = 0; k < seeds.size(); ++k) {
    const int s = seeds[k], end = k + 1 < seeds.size() ? seeds[k + 1] : n;
    const std::int32_t* b0 = &want[static_cast<std::size_t>(s) * 4];
    ASSERT_TRUE(t.init(frame(s), shle::Box{double(b0[0]), double(b0[1]), double(b0[0] + b0[2]),
                                           double(b0[1] + b0[3])}));
    for (int i = s + 1; i < end; ++i) {
      shle::Box b;
      EXPECT_EQ(t.update(frame(i), &b), ok[i] != 0) << "frame " << i;
      const std::int32_t* q = &want[static_cast<std::size_t>(i) * 4];
      const double d = std::max({std::fabs(b.x0 - q[0]), std::fabs(b.y0 - q[1]), std::fabs(b.width() - q[2]),
                                 std::fabs(b.height() - q[3])});
      EXPECT_LE(d, 1e-3) << "frame " << i << ": ours " << b.x0 << "," << b.y0 << ", OpenCV " << q[0] << ","
                         << q[1];
      max_diff = std::max(max_diff, d);
      ++tracked;
      moved += q[0] != b0[0] || q[1] != b0[1];
    }
  }
  EXPECT_GT(moved, 0);  // the drive moves the box: the comparison is not trivial
  std::printf("[ MIL ] %s: %d tracked frames over %zu seeds, max box difference %.6g px\n",
              st.metadata().at("scene").c_str(), tracked, seeds.size(), max_diff);
}

}  // namespace
