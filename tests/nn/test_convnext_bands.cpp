// ConvNeXt's banded blocks (depthwise and MLP fused per band of 8 image rows, every other
// block walking its rows upward) against the layer-by-layer path that a dump sink selects:
// the same output, bit for bit, for 1, 2 and 3 threads. No PyTorch needed: the
// agreement with torchvision is tests/reference/test_convnext_torch.cpp's.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "nn/models/convnext.h"
#include "nn/models/synthetic_weights.h"
#include "nn/threads.h"
#include "tests/counting_dump_sink.h"
#include "tests/nn/random_data.h"
#include "weights/safetensors.h"

namespace {

std::vector<float> run(nn::ConvNeXt& model, int n, int h, int w, const std::vector<float>& x) {
  model.plan(n, h, w);
  const nn::ConstTensorView y = model.forward(x.data());
  return std::vector<float>(y.data, y.data + y.count());
}

TEST(ConvNeXtBands, BitwiseTheLayerByLayerPathForEveryThreadCount) {
  // Two images of 160x200: stage 1 has 2 x 40 rows and stage 2 2 x 20, so both are banded
  // with up to 3 threads (a stage is banded when it has 16 rows per thread), and with one
  // thread stage 3 (2 x 10 rows) too. Two and three blocks per stage: both directions,
  // and with one thread a share spans both images.
  const nn::ConvNeXtConfig cfg{{16, 24, 32, 40}, {2, 3, 2, 1}};
  const auto st = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(cfg, "features."), 7).bytes(), "synthetic");
  nn::ConvNeXt model(st, "features.");
  const int n = 2, h = 160, w = 200;
  const std::vector<float> x = nntest::random_vector(static_cast<std::size_t>(n) * 3 * h * w, 11, -2.f, 2.f);
  std::vector<float> first;
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    nn::set_num_threads(threads);
    const std::vector<float> banded = run(model, n, h, w, x);
    testutil::CountingDumpSink sink;  // its presence alone makes every block unbanded
    model.set_dump(&sink);
    const std::vector<float> layered = run(model, n, h, w, x);
    model.set_dump(nullptr);
    ASSERT_GT(sink.tensors, 0) << "the dump sink was not used";
    ASSERT_EQ(banded.size(), layered.size());
    EXPECT_EQ(0, std::memcmp(banded.data(), layered.data(), banded.size() * sizeof(float)));
    if (first.empty()) first = banded;
    EXPECT_EQ(0, std::memcmp(first.data(), banded.data(), banded.size() * sizeof(float)));
  }
  nn::set_num_threads(0);
}

}  // namespace
