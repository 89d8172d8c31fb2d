#include "stixel/dbscan.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

#include "stixel/error.h"

namespace stixel {
namespace {

struct Box {
  double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
  void add(const Point2& p) {
    a0 = std::min(a0, p.a);
    a1 = std::max(a1, p.a);
    b0 = std::min(b0, p.b);
    b1 = std::max(b1, p.b);
  }
  bool empty() const { return a0 > a1; }
};

inline double dist2(const Point2& p, const Point2& q) {
  const double da = p.a - q.a, db = p.b - q.b;
  return da * da + db * db;
}

// Squared distance from p to the nearest point of box (0 inside).
inline double dist2(const Box& box, const Point2& p) {
  const double da = p.a < box.a0 ? box.a0 - p.a : (p.a > box.a1 ? p.a - box.a1 : 0.0);
  const double db = p.b < box.b0 ? box.b0 - p.b : (p.b > box.b1 ? p.b - box.b1 : 0.0);
  return da * da + db * db;
}

inline double dist2(const Box& x, const Box& y) {
  const double da = std::max({0.0, x.a0 - y.a1, y.a0 - x.a1});
  const double db = std::max({0.0, x.b0 - y.b1, y.b0 - x.b1});
  return da * da + db * db;
}

struct Cell {
  std::int64_t ca = 0, cb = 0;
  int begin = 0, end = 0;            // range in Workspace::order (all points)
  int core_begin = 0, core_end = 0;  // range in Workspace::core_order
  Box all, cores;
  bool cores_connected = true;       // every core of the cell is in one component
};

// The per-call buffers of one clustering run.
struct Workspace {
  std::vector<std::int64_t> ca, cb;
  std::vector<int> table, order, cell_of, core_order, parent, label_of_root;
  std::vector<char> core;
  std::vector<Cell> cells;
  std::vector<int> near_a, near_b;
};

// Occupied cells of a uniform grid. Points of a cell are listed in ascending
// index order, so every loop below visits them deterministically.
class Grid {
 public:
  Grid(const std::vector<Point2>& pts, double side, Workspace& ws) : ws_(ws) {
    const int n = static_cast<int>(pts.size());
    double amin = pts[0].a, bmin = pts[0].b, amax = amin, bmax = bmin;
    for (const Point2& p : pts) {
      amin = std::min(amin, p.a);
      amax = std::max(amax, p.a);
      bmin = std::min(bmin, p.b);
      bmax = std::max(bmax, p.b);
    }
    const double span = std::max(amax - amin, bmax - bmin) / side;
    if (!(span < 1e15)) throw Error("dbscan: coordinates span too wide for eps");
    std::vector<std::int64_t>& ca = ws.ca;
    std::vector<std::int64_t>& cb = ws.cb;
    ca.resize(n);
    cb.resize(n);
    const double inv = 1.0 / side;
    na_ = nb_ = 0;
    for (int i = 0; i < n; ++i) {
      // Non-negative, so truncation is floor.
      ca[i] = static_cast<std::int64_t>((pts[i].a - amin) * inv);
      cb[i] = static_cast<std::int64_t>((pts[i].b - bmin) * inv);
      na_ = std::max(na_, ca[i] + 1);
      nb_ = std::max(nb_, cb[i] + 1);
    }
    // A dense table for the usual compact scenes, sorting for sparse outliers.
    dense_ = na_ <= (1 << 24) && nb_ <= (1 << 24) &&
             na_ * nb_ <= std::max<std::int64_t>(16 * static_cast<std::int64_t>(n), 1 << 16);
    std::vector<int>& order = ws.order;
    std::vector<int>& cell_of = ws.cell_of;
    std::vector<Cell>& cells = ws.cells;
    order.resize(n);
    cell_of.resize(n);
    cells.clear();
    if (dense_) {
      // Counting sort by cell; `table` first counts, then maps cell -> index.
      std::vector<int>& table = ws.table;
      table.assign(static_cast<std::size_t>(na_ * nb_), 0);
      for (int i = 0; i < n; ++i) ++table[static_cast<std::size_t>(ca[i] * nb_ + cb[i])];
      int occupied = 0;
      for (int c : table) occupied += c != 0;
      cells.resize(occupied);
      int pos = 0, k = 0;
      for (std::size_t key = 0; key < table.size(); ++key) {
        const int count = table[key];
        if (!count) {
          table[key] = -1;
          continue;
        }
        Cell& c = cells[k];
        c = Cell();
        c.ca = static_cast<std::int64_t>(key) / nb_;
        c.cb = static_cast<std::int64_t>(key) % nb_;
        c.begin = c.end = pos;
        pos += count;
        table[key] = k++;
      }
      for (int i = 0; i < n; ++i) {
        const int c = table[static_cast<std::size_t>(ca[i] * nb_ + cb[i])];
        order[cells[c].end++] = i;
        cell_of[i] = c;
      }
    } else {
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
        return ca[x] != ca[y] ? ca[x] < ca[y] : cb[x] < cb[y];
      });
      for (int k = 0; k < n; ++k) {
        const int i = order[k];
        if (cells.empty() || cells.back().ca != ca[i] || cells.back().cb != cb[i]) {
          Cell c;
          c.ca = ca[i];
          c.cb = cb[i];
          c.begin = c.end = k;
          cells.push_back(c);
        }
        cells.back().end = k + 1;
        cell_of[i] = static_cast<int>(cells.size()) - 1;
      }
    }
    for (Cell& c : cells)
      for (int k = c.begin; k < c.end; ++k) c.all.add(pts[order[k]]);
  }

  // Occupied cell at (ca, cb), or -1.
  int find(std::int64_t ca, std::int64_t cb) const {
    if (ca < 0 || cb < 0 || ca >= na_ || cb >= nb_) return -1;
    if (dense_) return ws_.table[static_cast<std::size_t>(ca * nb_ + cb)];
    const std::vector<Cell>& cells = ws_.cells;
    auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(ca, cb),
                               [](const Cell& c, const std::pair<std::int64_t, std::int64_t>& k) {
                                 return c.ca != k.first ? c.ca < k.first : c.cb < k.second;
                               });
    if (it == cells.end() || it->ca != ca || it->cb != cb) return -1;
    return static_cast<int>(it - cells.begin());
  }

  // Calls fn(cell index) for the occupied cells within two steps of `cell`
  // (the cell itself first) until fn returns false. Two steps of a side just
  // under eps / sqrt 2 cover distance eps.
  template <class Fn>
  void for_neighbours(int cell, Fn fn) const {
    if (!fn(cell)) return;
    const Cell& c = ws_.cells[cell];
    for (std::int64_t da = -2; da <= 2; ++da)
      for (std::int64_t db = -2; db <= 2; ++db) {
        if (da == 0 && db == 0) continue;
        const int k = find(c.ca + da, c.cb + db);
        if (k >= 0 && !fn(k)) return;
      }
  }

 private:
  Workspace& ws_;
  std::int64_t na_ = 0, nb_ = 0;
  bool dense_ = false;
};

class DisjointSets {
 public:
  explicit DisjointSets(std::vector<int>& parent, int n) : parent_(parent) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(int x, int y) {
    x = find(x);
    y = find(y);
    if (x != y) parent_[std::max(x, y)] = std::min(x, y);
  }

 private:
  std::vector<int>& parent_;
};

}  // namespace

std::vector<int> dbscan(const std::vector<Point2>& pts, double eps, int min_samples) {
  if (!(eps > 0) || !std::isfinite(eps))
    throw Error("dbscan: eps must be positive, got " + std::to_string(eps));
  if (min_samples < 1)
    throw Error("dbscan: min_samples must be >= 1, got " + std::to_string(min_samples));
  const int n = static_cast<int>(pts.size());
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(pts[i].a) || !std::isfinite(pts[i].b))
      throw Error("dbscan: point " + std::to_string(i) + " has a non-finite coordinate");
  if (n == 0) return {};

  const double eps2 = eps * eps;
  Workspace ws;
  Grid grid(pts, eps / std::sqrt(2.0) * (1.0 - 1e-9), ws);
  std::vector<Cell>& cells = ws.cells;
  const std::vector<int>& order = ws.order;

  // 1. Core points: >= min_samples neighbours (itself included) within eps.
  std::vector<char>& core = ws.core;
  core.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    int count = 0;
    const Point2& p = pts[i];
    grid.for_neighbours(ws.cell_of[i], [&](int k) {
      const Cell& c = cells[k];
      if (dist2(c.all, p) > eps2) return true;
      for (int j = c.begin; j < c.end; ++j)
        if (dist2(p, pts[order[j]]) <= eps2 && ++count >= min_samples) return false;
      return true;
    });
    core[i] = count >= min_samples;
  }

  // 2. Components of the core graph (cores within eps of each other).
  std::vector<int>& core_order = ws.core_order;
  core_order.clear();
  DisjointSets sets(ws.parent, n);
  for (Cell& c : cells) {
    c.core_begin = static_cast<int>(core_order.size());
    for (int j = c.begin; j < c.end; ++j)
      if (core[order[j]]) {
        core_order.push_back(order[j]);
        c.cores.add(pts[order[j]]);
      }
    c.core_end = static_cast<int>(core_order.size());
    if (c.core_end - c.core_begin < 2) continue;
    // Cores of one cell are within eps of each other by the cell size; the check
    // keeps this exact even where rounding would disagree.
    const int rep = core_order[c.core_begin];
    for (int j = c.core_begin + 1; j < c.core_end; ++j) {
      if (dist2(pts[rep], pts[core_order[j]]) <= eps2)
        sets.unite(rep, core_order[j]);
      else
        c.cores_connected = false;
    }
    if (!c.cores_connected)
      for (int x = c.core_begin; x < c.core_end; ++x)
        for (int y = x + 1; y < c.core_end; ++y)
          if (dist2(pts[core_order[x]], pts[core_order[y]]) <= eps2)
            sets.unite(core_order[x], core_order[y]);
  }
  std::vector<int>& near_a = ws.near_a;
  std::vector<int>& near_b = ws.near_b;
  for (int ka = 0; ka < static_cast<int>(cells.size()); ++ka) {
    const Cell& A = cells[ka];
    if (A.core_begin == A.core_end) continue;
    grid.for_neighbours(ka, [&](int kb) {
      if (kb <= ka) return true;  // each pair of cells once
      const Cell& B = cells[kb];
      if (B.core_begin == B.core_end) return true;
      const bool whole = A.cores_connected && B.cores_connected;
      if (whole && sets.find(core_order[A.core_begin]) == sets.find(core_order[B.core_begin]))
        return true;
      if (dist2(A.cores, B.cores) > eps2) return true;
      near_a.clear();
      near_b.clear();
      for (int x = A.core_begin; x < A.core_end; ++x)
        if (dist2(B.cores, pts[core_order[x]]) <= eps2) near_a.push_back(core_order[x]);
      for (int y = B.core_begin; y < B.core_end; ++y)
        if (dist2(A.cores, pts[core_order[y]]) <= eps2) near_b.push_back(core_order[y]);
      for (int a : near_a)
        for (int b : near_b) {
          if (!whole && sets.find(a) == sets.find(b)) continue;
          if (dist2(pts[a], pts[b]) <= eps2) {
            sets.unite(a, b);
            if (whole) return true;  // one link joins both cells entirely
          }
        }
      return true;
    });
  }

  // 3. Labels in scikit-learn's order: clusters numbered by their lowest-index
  //    core point; border points take the lowest label among reachable clusters.
  std::vector<int> labels(n, -1);
  std::vector<int>& label_of_root = ws.label_of_root;
  label_of_root.assign(n, -1);
  int next = 0;
  for (int i = 0; i < n; ++i) {
    if (!core[i]) continue;
    const int r = sets.find(i);
    if (label_of_root[r] < 0) label_of_root[r] = next++;
    labels[i] = label_of_root[r];
  }
  for (int i = 0; i < n; ++i) {
    if (core[i]) continue;
    int best = INT_MAX;
    const Point2& p = pts[i];
    grid.for_neighbours(ws.cell_of[i], [&](int k) {
      const Cell& c = cells[k];
      if (c.core_begin == c.core_end || dist2(c.cores, p) > eps2) return true;
      for (int j = c.core_begin; j < c.core_end; ++j) {
        const int q = core_order[j];
        if (labels[q] < best && dist2(p, pts[q]) <= eps2) best = labels[q];
      }
      return best != 0;  // 0 is the lowest label there is
    });
    if (best != INT_MAX) labels[i] = best;
  }
  return labels;
}

}  // namespace stixel
