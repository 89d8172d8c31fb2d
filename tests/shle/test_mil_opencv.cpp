// The MIL tracker against OpenCV 4.6's own cv2.TrackerMIL on rendered sequences
// (tests/reference/shle_mil_ref.py, run at test time): the same boxes on every
// frame, one tracker re-seeded per sequence as one Python process runs them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "shle/mil_haar.h"
#include "shle/tracker.h"
#include "weights/safetensors.h"

namespace {

struct Sequence {
  std::string name;
  int width = 0, height = 0, frames = 0;
  std::vector<std::uint8_t> pixels;  // channel 0, frame after frame
  std::vector<std::int32_t> boxes;   // x, y, w, h per frame
  std::vector<std::uint8_t> ok;
  shle::GrayView frame(int i) const {
    return shle::GrayView{width, height, pixels.data() + static_cast<std::size_t>(i) * width * height};
  }
};

const weights::SafeTensors& reference() {
  static const weights::SafeTensors st =
      weights::SafeTensors::load(std::string(ROADNN_REF_DIR) + "/shle_mil.safetensors");
  return st;
}

template <typename T>
std::vector<T> copy(const weights::SafeTensors& st, const std::string& name) {
  std::vector<T> v(static_cast<std::size_t>(st.info(name).numel()));
  if (!v.empty()) std::memcpy(v.data(), st.raw(name), sizeof(T) * v.size());
  return v;
}

std::vector<Sequence> sequences() {
  const weights::SafeTensors& st = reference();
  std::vector<Sequence> out;
  std::stringstream ss(st.metadata().at("sequences"));
  std::string name;
  while (std::getline(ss, name, ',')) {
    Sequence s;
    s.name = name;
    const weights::TensorInfo& f = st.info(name + ".frames");
    EXPECT_EQ(f.dtype, weights::DType::U8);
    s.frames = static_cast<int>(f.shape.at(0));
    s.height = static_cast<int>(f.shape.at(1));
    s.width = static_cast<int>(f.shape.at(2));
    s.pixels = copy<std::uint8_t>(st, name + ".frames");
    EXPECT_EQ(st.info(name + ".boxes").dtype, weights::DType::I32);
    s.boxes = copy<std::int32_t>(st, name + ".boxes");
    s.ok = copy<std::uint8_t>(st, name + ".ok");
    out.push_back(std::move(s));
  }
  return out;
}

struct TrackRun {
  std::vector<std::vector<shle::Box>> boxes;  // per sequence, per frame (init box first)
  std::vector<std::vector<bool>> ok;
};

// One tracker through all sequences in the reference's order (its rand() stream
// continues from one seed to the next, as in one Python process).
TrackRun run(const std::vector<Sequence>& seqs, const shle::MilOptions& opt = {}) {
  TrackRun r;
  shle::MilTracker t(opt);
  for (const Sequence& s : seqs) {
    const std::int32_t* b0 = s.boxes.data();
    shle::Box seed{double(b0[0]), double(b0[1]), double(b0[0] + b0[2]), double(b0[1] + b0[3])};
    std::vector<shle::Box> boxes{seed};
    std::vector<bool> ok{t.init(s.frame(0), seed)};
    for (int i = 1; i < s.frames; ++i) {
      shle::Box b;
      ok.push_back(t.update(s.frame(i), &b));
      boxes.push_back(b);
    }
    r.boxes.push_back(boxes);
    r.ok.push_back(ok);
  }
  return r;
}

TEST(MilOpenCV, IntegralImageIsBitwiseOpenCVs) {
  const weights::SafeTensors& st = reference();
  const std::string of = st.metadata().at("integral_of");
  for (const Sequence& s : sequences()) {
    if (s.name != of) continue;
    shle::MilIntegral ii;
    shle::mil_integral(s.frame(0), shle::opencv_integral_lanes(), 3, &ii);
    std::vector<float> want = copy<float>(st, "integral");
    ASSERT_EQ(want.size(), ii.sum.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < want.size(); ++i) differ += want[i] != ii.sum[i];
    EXPECT_EQ(differ, 0u) << "of " << want.size() << " elements, lanes " << shle::opencv_integral_lanes();
    // The float rounding is real here: exact sums give other values.
    shle::MilIntegral plain;
    shle::mil_integral(s.frame(0), 0, 3, &plain);
    std::size_t plain_differ = 0;
    for (std::size_t i = 0; i < want.size(); ++i) plain_differ += want[i] != plain.sum[i];
    EXPECT_GT(plain_differ, 0u);
    return;
  }
  FAIL() << "no sequence " << of;
}

TEST(MilOpenCV, SameBoxesAsCv2TrackerMIL) {
  const std::vector<Sequence> seqs = sequences();
  ASSERT_GE(seqs.size(), 4u);
  const TrackRun r = run(seqs);
  for (std::size_t k = 0; k < seqs.size(); ++k) {
    const Sequence& s = seqs[k];
    double max_diff = 0;
    int frames_equal = 0;
    for (int i = 0; i < s.frames; ++i) {
      EXPECT_EQ(r.ok[k][i], s.ok[i] != 0) << s.name << " frame " << i;
      const std::int32_t* want = &s.boxes[static_cast<std::size_t>(i) * 4];
      const shle::Box& b = r.boxes[k][i];
      const double d = std::max({std::fabs(b.x0 - want[0]), std::fabs(b.y0 - want[1]),
                                 std::fabs(b.width() - want[2]), std::fabs(b.height() - want[3])});
      max_diff = std::max(max_diff, d);
      frames_equal += d <= 1e-3;
      EXPECT_LE(d, 1e-3) << s.name << " frame " << i << ": ours " << b.x0 << "," << b.y0 << " " << b.width()
                         << "x" << b.height() << ", OpenCV " << want[0] << "," << want[1] << " " << want[2] << "x"
                         << want[3];
    }
    std::printf("[ MIL ] %s: %d/%d frames equal, max box difference %.6g px\n", s.name.c_str(), frames_equal,
                s.frames, max_diff);
  }
}

TEST(MilOpenCV, DeterministicAndIndependentOfOtherTrackers) {
  const std::vector<Sequence> seqs = sequences();
  const TrackRun a = run(seqs);
  // Another tracker running meanwhile shares no state with these.
  shle::MilTracker other;
  shle::Box b;
  ASSERT_TRUE(other.init(seqs[0].frame(0), shle::Box{100, 80, 140, 110}));
  ASSERT_TRUE(other.update(seqs[0].frame(1), &b));
  const TrackRun c = run(seqs);
  for (std::size_t k = 0; k < seqs.size(); ++k)
    for (std::size_t i = 0; i < a.boxes[k].size(); ++i) {
      EXPECT_EQ(a.boxes[k][i].x0, c.boxes[k][i].x0);
      EXPECT_EQ(a.boxes[k][i].y0, c.boxes[k][i].y0);
    }
}

// Our CPU check picks the block width OpenCV's dispatcher picked in the reference run.
TEST(MilOpenCV, IntegralBlockWidthIsOpenCVsDispatch) {
  EXPECT_EQ(std::to_string(shle::opencv_integral_lanes()), reference().metadata().at("lanes"));
}

// OpenCV made to run its lower SIMD levels (AVX2, SSE4) on this CPU: a different
// rounding of the integral image, which the tracker follows with integral_lanes.
TEST(MilOpenCV, LowerSimdLevelsToo) {
  const weights::SafeTensors& st = reference();
  const std::vector<Sequence> seqs = sequences();
  const Sequence* drive = nullptr;
  for (const Sequence& s : seqs)
    if (s.name == st.metadata().at("integral_of")) drive = &s;
  ASSERT_NE(drive, nullptr);
  std::stringstream levels(st.metadata().at("levels"));
  std::string item;
  int checked = 0;
  while (std::getline(levels, item, ',')) {
    const std::string level = item.substr(0, item.find(':'));
    const int lanes = std::stoi(item.substr(item.find(':') + 1));
    shle::MilIntegral ii;
    shle::mil_integral(drive->frame(0), lanes, 3, &ii);
    const std::vector<float> want = copy<float>(st, level + ".integral");
    ASSERT_EQ(want.size(), ii.sum.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < want.size(); ++i) differ += want[i] != ii.sum[i];
    EXPECT_EQ(differ, 0u) << level << " (lanes " << lanes << ")";
    shle::MilOptions opt;
    opt.integral_lanes = lanes;
    Sequence alone = *drive;
    alone.boxes = copy<std::int32_t>(st, level + ".boxes");
    const TrackRun r = run({alone}, opt);
    double max_diff = 0;
    for (int i = 0; i < alone.frames; ++i) {
      const std::int32_t* w = &alone.boxes[static_cast<std::size_t>(i) * 4];
      const shle::Box& b = r.boxes[0][i];
      max_diff = std::max({max_diff, std::fabs(b.x0 - w[0]), std::fabs(b.y0 - w[1]), std::fabs(b.width() - w[2]),
                           std::fabs(b.height() - w[3])});
    }
    EXPECT_LE(max_diff, 1e-3) << level;
    std::printf("[ MIL ] %s at OpenCV's %s level (lanes %d): max box difference %.6g px\n", drive->name.c_str(),
                level.c_str(), lanes, max_diff);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

// The last sequence is the first scene again in a later tracker: OpenCV drew its
// features further along rand(), and a tracker starting the stream afresh
// (another process) must come out differently, or the test above proves little.
TEST(MilOpenCV, LaterSeedsContinueTheRandStream) {
  const std::vector<Sequence> seqs = sequences();
  const Sequence& again = seqs.back();
  ASSERT_EQ(again.name, "patch_again");
  const TrackRun fresh = run({again});
  int differ = 0;
  for (int i = 0; i < again.frames; ++i)
    differ += fresh.boxes[0][i].x0 != again.boxes[static_cast<std::size_t>(i) * 4] ||
              fresh.boxes[0][i].y0 != again.boxes[static_cast<std::size_t>(i) * 4 + 1];
  EXPECT_GT(differ, 0);
}

}  // namespace
