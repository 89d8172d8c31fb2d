#include "apps/nnrun/detection_outputs.h"

#include <vector>

namespace nnrun {

namespace {

std::vector<float> flat(const std::vector<nn::detection::Box>& boxes) {
  std::vector<float> v;
  v.reserve(4 * boxes.size());
  for (const auto& b : boxes) v.insert(v.end(), {b.x1, b.y1, b.x2, b.y2});
  return v;
}

}  // namespace

void write_detections(weights::Writer& out, const nn::detection::Detections& d, const std::string& label_name) {
  const std::int64_t k = static_cast<std::int64_t>(d.boxes.size());
  out.add_f32("boxes", {k, 4}, flat(d.boxes).data());
  out.add_f32("scores", {k}, d.scores.data());
  out.add_i64(label_name, {k}, d.labels.data());
}

void write_proposals(weights::Writer& out, const nn::detection::Proposals& p, const std::string& score_name,
                     const nn::detection::ImageSizes& sizes) {
  const std::int64_t n = static_cast<std::int64_t>(p.boxes.size());
  out.add_f32("proposals", {n, 4}, flat(p.boxes).data());
  out.add_f32(score_name, {n}, p.scores.data());
  const std::int64_t hw[2] = {sizes.resized_h, sizes.resized_w};
  out.add_i64("proposal_image_size", {2}, hw);
}

}  // namespace nnrun
