// Precision notes (all as in OpenCV 4.6's tracking_online_mil.cpp): stump
// parameters are float; batch means come from cv::mean (a double sum times
// 1.0 / n), the first variance from cv::meanStdDev (double sums, squared
// float standard deviation + 1e-9f); powf, logf and expf are the float
// functions of the C library; the bag likelihood takes a double log.
#include "shle/mil_boost.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>

namespace shle {
namespace {

float sigmoid(float x) { return 1.0f / (1.0f + std::exp(-x)); }

// cv::mean of one column of a row-major samples x features table.
float column_mean(const std::vector<float>& v, int n, int features, int k) {
  double s = 0;
  for (int j = 0; j < n; ++j) s += v[static_cast<std::size_t>(j) * features + k];
  return static_cast<float>(s * (n ? 1.0 / n : 0.0));
}

struct Ranked {
  float val;
  int ind;
};
bool ranked_less(const Ranked& a, const Ranked& b) { return a.val < b.val; }

}  // namespace

float MilBoost::Stump::classify(float x) const {
  const float d0 = x - mu0, d1 = x - mu1;
  const double log_p0 = d0 * d0 * e0 + log_n0;  // float expression, widened
  const double log_p1 = d1 * d1 * e1 + log_n1;
  return static_cast<float>(log_p1 - log_p0);
}

void MilBoost::reset(int features, int selected, float learning_rate) {
  features_ = std::max(0, features);
  select_ = std::min(std::max(0, selected), features_);
  rate_ = learning_rate;
  stumps_.assign(static_cast<std::size_t>(features_), Stump{});
  selected_.clear();
}

void MilBoost::update_stump(Stump* st, int k, const std::vector<float>& pos, int n_pos,
                            const std::vector<float>& neg, int n_neg) const {
  const int nf = features_;
  const float pos_mu = column_mean(pos, n_pos, nf, k), neg_mu = column_mean(neg, n_neg, nf, k);
  if (st->trained) {
    // mean((x - mu)^2) with x - mu and the square in float.
    auto blend = [&](const std::vector<float>& v, int n, float batch_mu, float* mu, float* sig) {
      *mu = rate_ * *mu + (1 - rate_) * batch_mu;
      double s = 0;
      for (int j = 0; j < n; ++j) {
        const float d = v[static_cast<std::size_t>(j) * nf + k] - *mu;
        s += d * d;
      }
      const float msq = static_cast<float>(s * (n ? 1.0 / n : 0.0));
      *sig = rate_ * *sig + (1 - rate_) * msq;
    };
    blend(pos, n_pos, pos_mu, &st->mu1, &st->sig1);
    blend(neg, n_neg, neg_mu, &st->mu0, &st->sig0);
  } else {
    st->trained = true;
    // cv::meanStdDev: sqrt(max(E[x^2] - E[x]^2, 0)) in double, squared in float.
    auto first = [&](const std::vector<float>& v, int n, float batch_mu, float* mu, float* sig) {
      *mu = batch_mu;
      double s = 0, sq = 0;
      for (int j = 0; j < n; ++j) {
        const float x = v[static_cast<std::size_t>(j) * nf + k];
        s += x;
        sq += static_cast<double>(x) * x;
      }
      const double scale = n ? 1.0 / n : 0.0;
      s *= scale;
      const float sd = static_cast<float>(std::sqrt(std::max(sq * scale - s * s, 0.0)));
      *sig = sd * sd + 1e-9f;
    };
    first(pos, n_pos, pos_mu, &st->mu1, &st->sig1);
    first(neg, n_neg, neg_mu, &st->mu0, &st->sig0);
  }
  st->log_n0 = std::log(1.0f / std::pow(st->sig0, 0.5f));
  st->log_n1 = std::log(1.0f / std::pow(st->sig1, 0.5f));
  st->e1 = -1.0f / (2.0f * st->sig1 + FLT_MIN);
  st->e0 = -1.0f / (2.0f * st->sig0 + FLT_MIN);
}

void MilBoost::update(const std::vector<float>& pos, int n_pos, const std::vector<float>& neg, int n_neg) {
  const int nf = features_;
  const std::size_t np = static_cast<std::size_t>(n_pos), nn = static_cast<std::size_t>(n_neg);
  pos_pred_.resize(static_cast<std::size_t>(nf) * np);
  neg_pred_.resize(static_cast<std::size_t>(nf) * nn);
  for (int m = 0; m < nf; ++m) {
    Stump& st = stumps_[static_cast<std::size_t>(m)];
    update_stump(&st, m, pos, n_pos, neg, n_neg);
    for (std::size_t j = 0; j < np; ++j) pos_pred_[m * np + j] = st.classify(pos[j * nf + m]);
    for (std::size_t j = 0; j < nn; ++j) neg_pred_[m * nn + j] = st.classify(neg[j * nf + m]);
  }
  h_pos_.assign(np, 0.0f);
  h_neg_.assign(nn, 0.0f);
  selected_.clear();
  std::vector<Ranked> ranked(static_cast<std::size_t>(nf));
  for (int s = 0; s < select_; ++s) {
    for (int w = 0; w < nf; ++w) {
      const float* pp = &pos_pred_[w * np];
      const float* npd = &neg_pred_[w * nn];
      float lll = 1.0f;
      for (std::size_t j = 0; j < np; ++j) lll *= (1 - sigmoid(h_pos_[j] + pp[j]));
      const float pos_likl = static_cast<float>(-std::log(static_cast<double>(1 - lll) + 1e-5));
      lll = 0.0f;
      for (std::size_t j = 0; j < nn; ++j) lll += -std::log(1e-5f + 1 - sigmoid(h_neg_[j] + npd[j]));
      ranked[static_cast<std::size_t>(w)] =
          Ranked{pos_likl / static_cast<float>(n_pos) + lll / static_cast<float>(n_neg), w};
    }
    // OpenCV sorts all stumps by likelihood (std::sort, so ties fall where
    // libstdc++'s introsort puts them) and takes the first not yet chosen.
    std::sort(ranked.begin(), ranked.end(), ranked_less);
    for (const Ranked& r : ranked)
      if (std::find(selected_.begin(), selected_.end(), r.ind) == selected_.end()) {
        selected_.push_back(r.ind);
        break;
      }
    const int pick = selected_.back();
    for (std::size_t j = 0; j < np; ++j) h_pos_[j] += pos_pred_[pick * np + j];
    for (std::size_t j = 0; j < nn; ++j) h_neg_[j] += neg_pred_[pick * nn + j];
  }
}

float MilBoost::score(const float* chosen_values) const {
  float res = 0.0f;
  for (std::size_t i = 0; i < selected_.size(); ++i)
    res += stumps_[static_cast<std::size_t>(selected_[i])].classify(chosen_values[i]);
  return res;
}

}  // namespace shle
