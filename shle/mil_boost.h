// The classifier of OpenCV 4.6's TrackerMIL: online Gaussian stumps, one per Haar
// feature (ClfOnlineStump), and the MILBoost selection over them (ClfMilBoost),
// in OpenCV's float/double mix so that scores and choices are bitwise its own.
#pragma once

#include <vector>

namespace shle {

class MilBoost {
 public:
  // `features` stumps, `selected` chosen per update, learning rate in float.
  void reset(int features, int selected, float learning_rate);
  // One update with the feature values of the positives and negatives, each
  // row-major samples x features. The first update sets each stump's mean and
  // variance from the batch, later ones blend them in; then the stumps are
  // chosen from scratch, all positives forming one noisy-OR bag.
  void update(const std::vector<float>& pos, int n_pos, const std::vector<float>& neg, int n_neg);
  // The chosen stumps in the order they were chosen.
  const std::vector<int>& selected() const { return selected_; }
  // Log-odds score of one sample from the values of the chosen features, in the
  // order of selected(): the float sum of their stump outputs.
  float score(const float* chosen_values) const;

 private:
  struct Stump {
    float mu0 = 0, mu1 = 0, sig0 = 1, sig1 = 1;
    float log_n0 = 0, log_n1 = 0, e0 = 0, e1 = 0;
    bool trained = false;
    float classify(float x) const;
  };
  void update_stump(Stump* s, int k, const std::vector<float>& pos, int n_pos, const std::vector<float>& neg,
                    int n_neg) const;

  int features_ = 0, select_ = 0;
  float rate_ = 0.85f;
  std::vector<Stump> stumps_;
  std::vector<int> selected_;
  // Scratch of update(), kept to reuse its storage.
  std::vector<float> pos_pred_, neg_pred_, h_pos_, h_neg_;
};

}  // namespace shle
