// Ray casting, shading and the stereo disturbance model of the synthetic scenes.
#include <algorithm>
#include <cmath>
#include <limits>

#include "shle/synth.h"
#include "shle/synth_materials.h"
#include "shle/synth_random.h"

namespace shle {
namespace synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kSky = -1, kGround = -2, kHills = -3;

struct Rgb {
  double r, g, b;
};

Rgb mix(Rgb a, Rgb b, double t) { return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t}; }
Rgb scale(Rgb a, double k) { return {a.r * k, a.g * k, a.b * k}; }

// Smooth value noise on a unit lattice and three octaves of it, in [0, 1].
double value_noise(double x, double y, std::uint64_t seed) {
  double fx = std::floor(x), fy = std::floor(y);
  std::int64_t ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  auto L = [&](std::int64_t a, std::int64_t b) {
    return unit(hash(seed, static_cast<std::uint64_t>(a), static_cast<std::uint64_t>(b)));
  };
  double a = L(ix, iy), b = L(ix + 1, iy), c = L(ix, iy + 1), d = L(ix + 1, iy + 1);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

double fbm(double x, double y, std::uint64_t seed) {
  return (value_noise(x, y, seed) + 0.5 * value_noise(2.03 * x, 2.03 * y, seed + 1) +
          0.25 * value_noise(4.1 * x, 4.1 * y, seed + 2)) /
         1.75;
}

double frac(double x) { return x - std::floor(x); }

struct Camera {
  double cx3[3];  // centre, world
  double c, s;    // cos / sin of the pitch (looking down positive)
  double fx, fy, px, py;
  // World direction of the ray through pixel (u, v); its parameter is camera depth.
  void ray(double u, double v, double w[3]) const {
    double a = (u - px) / fx, b = (v - py) / fy;
    w[0] = a;
    w[1] = -b * c - s;
    w[2] = -b * s + c;
  }
  // Camera-frame (x, y down, z) of a world point.
  void to_camera(const double p[3], double out[3]) const {
    double d0 = p[0] - cx3[0], d1 = p[1] - cx3[1], d2 = p[2] - cx3[2];
    out[0] = d0;
    out[1] = -c * d1 - s * d2;
    out[2] = -s * d1 + c * d2;
  }
};

// Slab test; returns the entry distance and the entered face (axis * 2 + (max side)).
bool hit_box(const Scene::Object& o, const double c[3], const double w[3], double* t_out, int* face) {
  double tmin = -kInf, tmax = kInf;
  int axis = 0, side = 0;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(w[a]) < 1e-15) {
      if (c[a] < o.lo[a] || c[a] > o.hi[a]) return false;
      continue;
    }
    double t1 = (o.lo[a] - c[a]) / w[a], t2 = (o.hi[a] - c[a]) / w[a];
    int s = 0;
    if (t1 > t2) {
      std::swap(t1, t2);
      s = 1;
    }
    if (t1 > tmin) {
      tmin = t1;
      axis = a;
      side = s;
    }
    tmax = std::min(tmax, t2);
    if (tmin > tmax) return false;
  }
  if (!(tmin > 1e-6)) return false;
  *t_out = tmin;
  *face = axis * 2 + side;
  return true;
}

bool hit_ellipsoid(const Scene::Object& o, const double c[3], const double w[3], double* t_out) {
  double oc[3], d[3];
  for (int a = 0; a < 3; ++a) {
    double centre = 0.5 * (o.lo[a] + o.hi[a]), r = 0.5 * (o.hi[a] - o.lo[a]);
    oc[a] = (c[a] - centre) / r;
    d[a] = w[a] / r;
  }
  double A = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double B = 2 * (oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2]);
  double C = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - 1;
  double disc = B * B - 4 * A * C;
  if (disc < 0) return false;
  double t = (-B - std::sqrt(disc)) / (2 * A);
  if (!(t > 1e-6)) return false;
  *t_out = t;
  return true;
}

struct Surface {
  Rgb colour;
  double strength;  // stereo texture strength in [0, 1]
};

// Colour and texture strength of a surface point; (s, t) are in-plane metres.
Surface shade_material(int material, double s, double t, const double p[3], std::uint64_t seed) {
  double n = fbm(s * 6.0, t * 6.0, seed + 17 * material);
  switch (material) {
    case kStripes: {
      bool yellow = frac((s + t) / 0.5) < 0.5;
      Rgb base = yellow ? Rgb{0.95, 0.78, 0.1} : Rgb{0.08, 0.08, 0.08};
      return {scale(base, 0.85 + 0.3 * n), 0.95};
    }
    case kSign: {
      bool border = std::fabs(p[0]) > 0.6;
      double ink = fbm(s * 9.0, t * 9.0, seed + 99);
      Rgb base = border ? Rgb{0.8, 0.1, 0.1} : (ink > 0.62 ? Rgb{0.1, 0.1, 0.1} : Rgb{0.93, 0.93, 0.93});
      return {scale(base, 0.9 + 0.2 * n), 0.7};
    }
    case kPost:
      return {scale(Rgb{0.62, 0.63, 0.65}, 0.92 + 0.16 * n), 0.3};
    case kConcrete:
      return {scale(Rgb{0.63, 0.6, 0.56}, 0.7 + 0.6 * fbm(s * 3.0, t * 3.0, seed + 5)), 0.6};
    case kConcreteDark:
      return {scale(Rgb{0.45, 0.43, 0.41}, 0.7 + 0.6 * fbm(s * 3.0, t * 3.0, seed + 6)), 0.55};
    case kRailing:
      return {scale(Rgb{0.35, 0.36, 0.38}, 0.8 + 0.4 * n), 0.5};
    case kCable:
      return {scale(Rgb{0.12, 0.12, 0.13}, 0.8 + 0.4 * n), 0.55};
    case kFoliage:
      return {scale(Rgb{0.16, 0.33, 0.12}, 0.45 + 1.1 * fbm(s * 7.0, t * 7.0, seed + 7)), 0.85};
    case kTrunk:
      return {scale(Rgb{0.3, 0.22, 0.15}, 0.7 + 0.6 * n), 0.6};
    case kFacade: {
      bool window = frac(s / 2.5) > 0.25 && frac(s / 2.5) < 0.75 && frac(t / 3.0) > 0.35 && frac(t / 3.0) < 0.8;
      Rgb base = window ? Rgb{0.2, 0.24, 0.3} : Rgb{0.72, 0.66, 0.58};
      return {scale(base, 0.85 + 0.3 * n), 0.65};
    }
  }
  return {Rgb{1, 0, 1}, 0.5};
}

Surface shade_ground(const double p[3], std::uint64_t seed) {
  double x = p[0], z = p[2], ax = std::fabs(x);
  double n = fbm(x * 12.0, z * 12.0, seed + 3);
  if (ax > 5.0) return {scale(Rgb{0.25, 0.38, 0.15}, 0.6 + 0.8 * fbm(x * 4.0, z * 4.0, seed + 4)), 0.75};
  if (ax > 3.9) return {scale(Rgb{0.55, 0.55, 0.52}, 0.85 + 0.3 * n), 0.5};
  bool centre_line = ax < 0.08 && frac(z / 12.0) < 0.5;
  bool edge_line = std::fabs(ax - 3.6) < 0.08;
  if (centre_line || edge_line) return {scale(Rgb{0.9, 0.9, 0.88}, 0.95 + 0.1 * n), 0.35};
  return {scale(Rgb{0.33, 0.33, 0.34}, 0.7 + 0.6 * n), 0.7};
}

double hill_height(double x, std::uint64_t seed) { return 25.0 + 40.0 * fbm(x / 120.0, 0.5, seed + 11); }

}  // namespace

Frame Scene::render(int index) const {
  const SceneSpec& S = spec_;
  if (index < 0 || index >= frame_count()) return Frame{};
  const int W = S.width, H = S.height;
  const std::size_t N = static_cast<std::size_t>(W) * H;
  const std::uint64_t fseed = hash(S.seed, 0x6672ull, static_cast<std::uint64_t>(index));
  const std::uint64_t tseed = hash(S.seed, 0x7478ull);  // textures are fixed per scene
  Frame out;
  out.distance = distance_[index];
  out.pitch_deg = pitch_deg_[index];
  out.camera_height = cam_height_[index];
  Camera cam;
  cam.cx3[0] = 0;
  cam.cx3[1] = cam_height_[index];
  cam.cx3[2] = device_z_ - distance_[index];
  double th = pitch_deg_[index] * M_PI / 180.0;
  cam.c = std::cos(th);
  cam.s = std::sin(th);
  cam.fx = S.fx;
  cam.fy = S.fy;
  cam.px = S.cx;
  cam.py = S.cy;

  std::vector<double> depth(N, kInf);
  std::vector<int> id(N, kSky);
  std::vector<signed char> face(N, 0);
  const double hills_z = device_z_ + 700.0;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      double w[3];
      cam.ray(u, v, w);
      std::size_t i = static_cast<std::size_t>(v) * W + u;
      if (w[1] < 0) {
        double t = cam.cx3[1] / -w[1];
        depth[i] = t;
        id[i] = kGround;
      }
      if (w[2] > 0) {
        double t = (hills_z - cam.cx3[2]) / w[2];
        double y = cam.cx3[1] + t * w[1];
        if (t < depth[i] && y >= 0 && y <= hill_height(t * w[0], tseed)) {
          depth[i] = t;
          id[i] = kHills;
        }
      }
    }
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    const Object& o = objects_[k];
    // Screen rectangle of the object from its corners, or the whole image when
    // a corner is close to or behind the camera.
    int u0 = 0, u1 = W - 1, v0 = 0, v1 = H - 1;
    bool all_in_front = true, any_in_front = false;
    double umin = kInf, umax = -kInf, vmin = kInf, vmax = -kInf;
    for (int corner = 0; corner < 8; ++corner) {
      double p[3] = {corner & 1 ? o.hi[0] : o.lo[0], corner & 2 ? o.hi[1] : o.lo[1], corner & 4 ? o.hi[2] : o.lo[2]};
      double q[3];
      cam.to_camera(p, q);
      if (q[2] <= 0.05) {
        all_in_front = false;
        continue;
      }
      any_in_front = true;
      umin = std::min(umin, S.cx + S.fx * q[0] / q[2]);
      umax = std::max(umax, S.cx + S.fx * q[0] / q[2]);
      vmin = std::min(vmin, S.cy + S.fy * q[1] / q[2]);
      vmax = std::max(vmax, S.cy + S.fy * q[1] / q[2]);
    }
    if (!any_in_front) continue;
    if (all_in_front) {
      if (umax < 0 || vmax < 0 || umin > W - 1 || vmin > H - 1) continue;
      u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
      u1 = std::min(W - 1, static_cast<int>(std::ceil(umax)) + 1);
      v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
      v1 = std::min(H - 1, static_cast<int>(std::ceil(vmax)) + 1);
    }
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) {
        double w[3], t;
        int f = 6;
        cam.ray(u, v, w);
        bool hit = o.ellipsoid ? hit_ellipsoid(o, cam.cx3, w, &t) : hit_box(o, cam.cx3, w, &t, &f);
        std::size_t i = static_cast<std::size_t>(v) * W + u;
        if (hit && t < depth[i]) {
          depth[i] = t;
          id[i] = static_cast<int>(k);
          face[i] = static_cast<signed char>(f);
        }
      }
  }

  // Shading and the per-pixel texture strength that drives the stereo errors.
  out.image.width = W;
  out.image.height = H;
  out.image.rgb.resize(3 * N);
  std::vector<double> strength(N, 0.0);
  const double L[3] = {0.35, 0.8, -0.48};
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      std::size_t i = static_cast<std::size_t>(v) * W + u;
      double w[3];
      cam.ray(u, v, w);
      Rgb colour;
      double norm = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      double elev = w[1] / norm;
      Rgb horizon{0.84, 0.87, 0.9};
      if (id[i] == kSky) {
        Rgb zenith{0.42, 0.58, 0.84};
        colour = mix(horizon, zenith, std::min(1.0, std::max(0.0, elev * 3.0)));
        double cloud = fbm(w[0] / w[2] * 3.0, elev * 12.0, tseed + 21);
        colour = mix(colour, Rgb{0.95, 0.95, 0.96}, std::max(0.0, cloud - 0.55) * 1.5);
        strength[i] = 0.0;
      } else {
        double t = depth[i];
        double p[3] = {cam.cx3[0] + t * w[0], cam.cx3[1] + t * w[1], cam.cx3[2] + t * w[2]};
        Surface sf;
        double n[3] = {0, 1, 0};
        if (id[i] == kGround) {
          sf = shade_ground(p, tseed);
        } else if (id[i] == kHills) {
          sf = {scale(Rgb{0.33, 0.42, 0.33}, 0.8 + 0.4 * fbm(p[0] / 8.0, p[1] / 8.0, tseed + 12)), 0.35};
          n[1] = 0;
          n[2] = -1;
        } else {
          const Object& o = objects_[id[i]];
          double s, tt;
          if (o.ellipsoid) {
            for (int a = 0; a < 3; ++a) n[a] = (p[a] - 0.5 * (o.lo[a] + o.hi[a])) / (0.5 * (o.hi[a] - o.lo[a]));
            s = p[0] + 0.7 * p[2];
            tt = p[1];
          } else {
            int axis = face[i] / 2;
            n[0] = n[1] = n[2] = 0;
            n[axis] = face[i] % 2 ? 1 : -1;
            s = axis == 0 ? p[2] : p[0];
            tt = axis == 1 ? p[2] : p[1];
          }
          sf = shade_material(o.material, s, tt, p, tseed);
        }
        double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double lambert = std::max(0.0, (n[0] * L[0] + n[1] * L[1] + n[2] * L[2]) / nn);
        colour = scale(sf.colour, 0.55 + 0.5 * lambert);
        colour = mix(colour, horizon, 1.0 - std::exp(-t / 900.0));
        strength[i] = sf.strength;
      }
      std::uint64_t hp = hash(fseed, 0x7069ull, i);
      double c3[3] = {colour.r, colour.g, colour.b};
      for (int ch = 0; ch < 3; ++ch) {
        double val = c3[ch] * 255.0 + 1.5 * normal(hp + ch);
        out.image.rgb[3 * i + ch] = static_cast<std::uint8_t>(std::min(255.0, std::max(0.0, std::round(val))));
      }
    }

  // True device box: the bounding box of the device's pixels.
  int du0 = W, du1 = -1, dv0 = H, dv1 = -1;
  std::size_t device_pixels = 0;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      int k = id[static_cast<std::size_t>(v) * W + u];
      if (k >= 0 && objects_[k].device) {
        ++device_pixels;
        du0 = std::min(du0, u);
        du1 = std::max(du1, u);
        dv0 = std::min(dv0, v);
        dv1 = std::max(dv1, v);
      }
    }
  out.visible = device_pixels >= 20;
  if (out.visible) out.box = Box{double(du0), double(dv0), double(du1 + 1), double(dv1 + 1)};

  // Stereo disturbances on the true disparity bf / Z.
  const double bf = S.baseline * S.fx;
  std::vector<double> clean(N, 0.0);
  for (std::size_t i = 0; i < N; ++i)
    if (id[i] != kSky && depth[i] < kInf) clean[i] = bf / depth[i];
  out.disparity.assign(N, 0);
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      std::size_t i = static_cast<std::size_t>(v) * W + u;
      std::uint64_t hp = hash(fseed, 0x6470ull, i);
      double d = clean[i], s = strength[i];
      bool sky = id[i] == kSky;
      // Matching windows straddling a depth edge take the nearer surface.
      if (unit(hp) < 0.5) {
        double best = d;
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du) {
            int uu = u + du, vv = v + dv;
            if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
            best = std::max(best, clean[static_cast<std::size_t>(vv) * W + uu]);
          }
        if (best > d * 1.03 + 1e-9) {
          d = best;
          s = 0.8;
          sky = false;
        }
      }
      double r = unit(mix64(hp + 1));
      double p_drop = sky ? 0.985 : 0.01 + 0.85 * (1 - s) * (1 - s);
      double p_mis = sky ? 0.015 : 0.002 + 0.02 * (1 - s);
      double value;
      if (r < p_drop) {
        value = 0;
      } else if (r < p_drop + p_mis) {
        value = uniform(0.2, 24.0, mix64(hp + 2));
      } else {
        double z = bf / d;
        double sigma = (S.noise_near + S.noise_far * std::min(z, 300.0) / 70.0) * (1.0 + 1.5 * (1.0 - s));
        double block = normal(hash(fseed, 0x626cull, static_cast<std::uint64_t>(u / 8), static_cast<std::uint64_t>(v / 8)));
        value = d + sigma * (0.5 * block + normal(mix64(hp + 3)));
      }
      double raw = std::round(value * 32.0);
      out.disparity[i] = raw <= 0 ? 0 : static_cast<std::uint16_t>(std::min(raw, 65535.0));
    }

  // Simulated detector: misses (runs of them), jittered true box, distractors.
  if (out.visible) {
    bool missed = false;
    {
      // Two-state chain: stationary miss fraction = miss_rate, mean run length 2.
      double a = S.miss_rate >= 1 ? 1 : 0.5 * S.miss_rate / (1 - S.miss_rate);
      bool state = false;
      for (int k = 0; k <= index; ++k) {
        double q = unit(hash(S.seed, 0x6d73ull, static_cast<std::uint64_t>(k)));
        state = state ? q < 0.5 : q < a;
      }
      missed = state;
    }
    std::uint64_t ds = hash(fseed, 0x6474ull);
    if (!missed) {
      const Box& b = out.box;
      double jw = 2.0 + 0.03 * b.width(), jh = 2.0 + 0.03 * b.height();
      Box j{b.x0 + jw * normal(ds + 1), b.y0 + jh * normal(ds + 2), b.x1 + jw * normal(ds + 3),
            b.y1 + jh * normal(ds + 4)};
      j.x0 = std::max(0.0, j.x0);
      j.y0 = std::max(0.0, j.y0);
      j.x1 = std::min(double(W), std::max(j.x1, j.x0 + 4));
      j.y1 = std::min(double(H), std::max(j.y1, j.y0 + 4));
      out.detections.push_back(Candidate{j, uniform(0.55, 0.99, ds + 5)});
    }
    const double fw = W / 1280.0, fh = H / 720.0;
    auto add = [&](std::uint64_t h, double x0, double w, double y0, double hgt, double smin, double smax) {
      out.detections.push_back(Candidate{Box{x0 * fw, y0 * fh, (x0 + w) * fw, (y0 + hgt) * fh},
                                         uniform(smin, smax, h + 9)});
    };
    std::uint64_t h1 = ds + 100, h2 = ds + 200, h3 = ds + 300, h4 = ds + 400;
    if (unit(h1) < 0.4)  // a sign on the left
      add(h1, uniform(20, 380, h1 + 1), uniform(60, 200, h1 + 2), uniform(150, 330, h1 + 3), uniform(40, 120, h1 + 4),
          0.35, 0.97);
    if (unit(h2) < 0.35)  // a vehicle in the lower half
      add(h2, uniform(100, 900, h2 + 1), uniform(150, 380, h2 + 2), uniform(380, 500, h2 + 3),
          uniform(80, 200, h2 + 4), 0.35, 0.95);
    if (unit(h3) < 0.3)  // foliage at the top edge
      add(h3, uniform(0, 1000, h3 + 1), uniform(100, 280, h3 + 2), uniform(0, 0.8, h3 + 3), uniform(60, 200, h3 + 4),
          0.35, 0.9);
    if (unit(h4) < 0.5)  // low-confidence clutter
      add(h4, uniform(600, 1000, h4 + 1), uniform(40, 250, h4 + 2), uniform(60, 300, h4 + 3),
          uniform(20, 80, h4 + 4), 0.05, 0.3);
  }
  return out;
}

}  // namespace synth
}  // namespace shle
