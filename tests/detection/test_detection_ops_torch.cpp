// RoIAlign, NMS, batched NMS, the anchor table and box decoding against
// torchvision.ops / torchvision.models.detection (detector_ops_ref.py).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "nn/layout.h"
#include "nn/models/detection/anchors.h"
#include "nn/models/detection/box_ops.h"
#include "nn/models/detection/roi_align.h"
#include "tests/detection/match.h"
#include "tests/nn/isa_param.h"
#include "tests/reference/torch_ref.h"

namespace {

namespace det = nn::detection;

// On every ISA: within 2e-6 of torchvision, and the same bits as the scalar kernel.
void check_roi_align(const std::string& name) {
  weights::SafeTensors r = reftest::load_ref("det_ops_roi_align_" + name + ".safetensors");
  const auto& fs = r.info("feature").shape;
  const int c = static_cast<int>(fs[1]), h = static_cast<int>(fs[2]), w = static_cast<int>(fs[3]);
  const auto f = r.f32("feature");
  std::vector<float> nhwc(f.size());
  nn::nchw_to_nhwc(f.data(), 1, c, h, w, nhwc.data());
  const auto rois = dettest::to_boxes(r.f32("rois"));
  const auto expected = r.f32("expected");
  det::RoiAlignParams p;
  p.spatial_scale = r.f32("scale")[0];
  p.sampling_ratio = static_cast<int>(r.i64("sampling")[0]);
  std::vector<float> scalar;
  for (nn::Isa isa : nntest::supported_isas()) {
    SCOPED_TRACE(nn::isa_name(isa));
    nntest::IsaScope scope(isa);
    std::vector<float> ours(expected.size()), one(49 * c);
    for (std::size_t i = 0; i < rois.size(); ++i) {
      det::roi_align_one(nn::ConstTensorView(nhwc.data(), {1, h, w, c}), 0, rois[i], p, one.data());
      for (int ch = 0; ch < c; ++ch)
        for (int yx = 0; yx < 49; ++yx) ours[(i * c + ch) * 49 + yx] = one[yx * c + ch];
    }
    // Same samples and weights; only the summation order over the 4 corners may differ.
    reftest::expect_close_abs(ours.data(), expected, 2e-6, "roi_align " + name);
    if (scalar.empty()) scalar = ours;
    EXPECT_EQ(0, std::memcmp(scalar.data(), ours.data(), ours.size() * sizeof(float))) << "differs from scalar";
  }
}

TEST(DetectionOpsTorch, RoiAlignScale32) { check_roi_align("s32"); }
TEST(DetectionOpsTorch, RoiAlignScale4) { check_roi_align("s4"); }
TEST(DetectionOpsTorch, RoiAlignAdaptiveSampling) { check_roi_align("adaptive"); }

std::vector<int> to_int(const std::vector<std::int64_t>& v) { return std::vector<int>(v.begin(), v.end()); }

TEST(DetectionOpsTorch, NmsStrictIouAndOrder) {
  weights::SafeTensors r = reftest::load_ref("det_ops_nms.safetensors");
  const auto boxes = dettest::to_boxes(r.f32("boxes"));
  const auto keep = det::nms(boxes, r.f32("scores"), 0.5);
  EXPECT_EQ(keep, to_int(r.i64("keep")));
  // The exact-IoU-0.5 pair (indices n-4, n-3) both survive; the 0.51 pair does not.
  const int n = static_cast<int>(boxes.size());
  EXPECT_NE(std::find(keep.begin(), keep.end(), n - 3), keep.end());
  EXPECT_EQ(std::find(keep.begin(), keep.end(), n - 1), keep.end());
}

TEST(DetectionOpsTorch, NmsTiesKeepIndexOrder) {
  // Three identical boxes with equal scores: the lowest index wins.
  std::vector<det::Box> b(3, det::Box{0, 0, 10, 10});
  EXPECT_EQ(det::nms(b, {0.5f, 0.5f, 0.5f}, 0.5), std::vector<int>{0});
  EXPECT_EQ(det::nms(b, {0.4f, 0.5f, 0.5f}, 0.5), std::vector<int>{1});
}

void check_batched(const std::string& name) {
  weights::SafeTensors r = reftest::load_ref("det_ops_" + name + ".safetensors");
  const auto keep = det::batched_nms(dettest::to_boxes(r.f32("boxes")), r.f32("scores"), to_int(r.i64("classes")), 0.7);
  EXPECT_EQ(keep, to_int(r.i64("keep"))) << name;
}

TEST(DetectionOpsTorch, BatchedNmsCoordinateTrickPath) { check_batched("batched_small"); }
TEST(DetectionOpsTorch, BatchedNmsPerClassPath) { check_batched("batched_large"); }

void check_anchors(const std::string& name, const std::vector<std::vector<float>>& sizes) {
  weights::SafeTensors r = reftest::load_ref("det_ops_anchors_" + name + ".safetensors");
  const auto grids = r.i64("grids");
  const auto padded = r.i64("padded");
  std::vector<float> ours;
  for (std::size_t l = 0; l < sizes.size(); ++l) {
    const auto cell = det::cell_anchors(sizes[l], {0.5f, 1.0f, 2.0f});
    for (const det::Box& b : det::grid_anchors(cell, static_cast<int>(grids[2 * l]), static_cast<int>(grids[2 * l + 1]),
                                               static_cast<int>(padded[0]), static_cast<int>(padded[1])))
      ours.insert(ours.end(), {b.x1, b.y1, b.x2, b.y2});
  }
  const auto expected = r.f32("anchors");
  ASSERT_EQ(ours.size(), expected.size()) << name;
  reftest::expect_close_abs(ours.data(), expected, 0.0, "anchors " + name);
}

TEST(DetectionOpsTorch, AnchorTableMobileNet) {
  const std::vector<float> s = {32, 64, 128, 256, 512};
  check_anchors("mobile", {s, s, s});
  // The reference's 15 cell anchors (a = ratio_idx * 5 + size_idx).
  const auto cell = det::cell_anchors(s, {0.5f, 1.0f, 2.0f});
  ASSERT_EQ(cell.size(), 15u);
  EXPECT_EQ(cell[0].x1, -23.0f);
  EXPECT_EQ(cell[0].y1, -11.0f);
  EXPECT_EQ(cell[14].x2, 181.0f);
  EXPECT_EQ(cell[14].y2, 362.0f);
}

TEST(DetectionOpsTorch, AnchorTableResNetWithPoolStrideQuirk) {
  check_anchors("resnet", {{32}, {64}, {128}, {256}, {512}});
}

TEST(DetectionOpsTorch, BoxDecodeWithClamp) {
  weights::SafeTensors r = reftest::load_ref("det_ops_decode.safetensors");
  const auto ref = dettest::to_boxes(r.f32("ref"));
  const auto deltas = r.f32("deltas");
  std::vector<float> ours;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const det::Box b = det::decode_box(ref[i], deltas.data() + 4 * i, {10, 10, 5, 5});
    ours.insert(ours.end(), {b.x1, b.y1, b.x2, b.y2});
  }
  // exp() may differ from PyTorch's vectorised exp by an ulp.
  reftest::expect_close_rel_max(ours.data(), r.f32("expected"), 1e-6, "decode");
}

}  // namespace
