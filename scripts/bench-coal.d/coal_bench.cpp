// Times coal (C++, the library behind Pinocchio's collision checking) on a problem written by
// scripts/bench-coal.d/problem.py from `rl scene dump --random N`: the same shapes (meshes loaded
// by coal's own assimp loader as BVHModel<OBBRSS>, as Pinocchio loads them), the same pairs and
// the same configurations that `rl scene bench --configs N` times. Prints one JSON line.
//
// Queries (as Pinocchio's computeCollisions / computeDistances do them, with coal's cached
// ComputeCollision / ComputeDistance functors and default requests):
//   self_collision        any self pair colliding? (stops at the first)
//   environment           any robot–obstacle pair colliding? (stops at the first)
//   self_distance         the smallest distance over the self pairs (with nearest points)
//   environment_distance  the smallest distance over the robot–obstacle pairs
// Per configuration the transforms are set first (untimed), then the query repeats enough
// times for ~20 µs; the figure is the mean ns per query over all configurations, median over
// the rounds.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <coal/collision.h>
#include <coal/distance.h>
#include <coal/mesh_loader/loader.h>
#include <coal/shape/convex.h>
#include <coal/shape/geometric_shapes.h>
#include <coal/BVH/BVH_model.h>

using namespace coal;
using Clock = std::chrono::steady_clock;

static std::shared_ptr<CollisionGeometry> read_shape(std::istream& in) {
  std::string kind;
  in >> kind;
  if (kind == "box") { double x, y, z; in >> x >> y >> z; return std::make_shared<Box>(x, y, z); }
  if (kind == "sphere") { double r; in >> r; return std::make_shared<Sphere>(r); }
  if (kind == "cylinder") { double r, l; in >> r >> l; return std::make_shared<Cylinder>(r, l); }
  if (kind == "capsule") { double r, l; in >> r >> l; return std::make_shared<Capsule>(r, l); }
  if (kind == "cone") { double r, l; in >> r >> l; return std::make_shared<Cone>(r, l); }
  if (kind == "meshfile") {
    std::string path; double sx, sy, sz;
    in >> path >> sx >> sy >> sz;
    MeshLoader loader;
    return loader.load(path, Vec3s(sx, sy, sz));
  }
  if (kind == "mesh" || kind == "convex") {
    size_t nv, nt; in >> nv >> nt;
    std::vector<Vec3s> v(nv);
    for (auto& p : v) in >> p[0] >> p[1] >> p[2];
    std::vector<Triangle> t(nt);
    for (auto& tri : t) { size_t a, b, c; in >> a >> b >> c; tri.set(a, b, c); }
    if (kind == "convex") {
      return std::shared_ptr<CollisionGeometry>(ConvexBase::convexHull(v.data(), (unsigned int)v.size(), false, nullptr));
    }
    auto m = std::make_shared<BVHModel<OBBRSS>>();
    m->beginModel();
    m->addSubModel(v, t);
    m->endModel();
    return m;
  }
  throw std::runtime_error("unknown shape kind " + kind);
}

template <class F>
static double per_query(size_t configs, int rounds, F&& query) {
  // Calibrate repetitions on configuration 0: ~20 µs of work per configuration.
  auto t0 = Clock::now();
  volatile bool sink = query(0);
  double once = std::max(2e-8, std::chrono::duration<double>(Clock::now() - t0).count());
  size_t reps = std::min<size_t>(1000, std::max<size_t>(1, (size_t)(2e-5 / once + 0.999)));
  std::vector<double> samples;
  for (int r = 0; r < rounds; ++r) {
    double total = 0;
    for (size_t c = 0; c < configs; ++c) {
      auto t = Clock::now();
      for (size_t k = 0; k < reps; ++k) sink = query(c);
      total += std::chrono::duration<double>(Clock::now() - t).count();
    }
    samples.push_back(total * 1e9 / double(configs * reps));
  }
  (void)sink;
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

int main(int argc, char** argv) {
  if (argc < 3) { std::cerr << "usage: coal_bench PROBLEM ROUNDS\n"; return 2; }
  std::ifstream in(argv[1]);
  int rounds = std::atoi(argv[2]);
  std::string word;
  size_t n;
  in >> word >> n;  // shapes N
  std::vector<std::shared_ptr<CollisionGeometry>> shapes;
  for (size_t i = 0; i < n; ++i) shapes.push_back(read_shape(in));
  auto read_pairs = [&](void) {
    size_t k; std::string a, b; in >> a >> b >> k;
    std::vector<std::pair<size_t, size_t>> p(k);
    for (auto& x : p) in >> x.first >> x.second;
    return p;
  };
  auto self_pairs = read_pairs();
  auto env_pairs = read_pairs();
  size_t configs; in >> word >> configs;
  std::vector<std::vector<Transform3s>> tf(configs, std::vector<Transform3s>(n));
  for (auto& cfg : tf)
    for (auto& t : cfg) {
      double x, y, z, qx, qy, qz, qw;
      in >> x >> y >> z >> qx >> qy >> qz >> qw;
      t = Transform3s(Quatf(qw, qx, qy, qz).normalized(), Vec3s(x, y, z));
    }
  if (!in) { std::cerr << "coal_bench: truncated problem file\n"; return 2; }
  auto functors = [&](const std::vector<std::pair<size_t, size_t>>& p) {
    std::vector<ComputeCollision> cc; std::vector<ComputeDistance> cd;
    for (auto& [i, j] : p) { cc.emplace_back(shapes[i].get(), shapes[j].get()); cd.emplace_back(shapes[i].get(), shapes[j].get()); }
    return std::make_pair(std::move(cc), std::move(cd));
  };
  auto [self_cc, self_cd] = functors(self_pairs);
  auto [env_cc, env_cd] = functors(env_pairs);
  CollisionRequest creq;
  DistanceRequest dreq;
  auto collide = [&](auto& pairs, auto& cc, size_t c) {
    for (size_t k = 0; k < pairs.size(); ++k) {
      CollisionResult res;
      if (cc[k](tf[c][pairs[k].first], tf[c][pairs[k].second], creq, res)) return true;
    }
    return false;
  };
  auto distance = [&](auto& pairs, auto& cd, size_t c) {
    double best = 1e300;
    for (size_t k = 0; k < pairs.size(); ++k) {
      DistanceResult res;
      best = std::min<double>(best, cd[k](tf[c][pairs[k].first], tf[c][pairs[k].second], dreq, res));
    }
    return best < 0.5;
  };
  size_t self_colliding = 0;
  for (size_t c = 0; c < configs; ++c) self_colliding += collide(self_pairs, self_cc, c);
  double sc = per_query(configs, rounds, [&](size_t c) { return collide(self_pairs, self_cc, c); });
  double sd = per_query(configs, rounds, [&](size_t c) { return distance(self_pairs, self_cd, c); });
  double ec = env_pairs.empty() ? 0 : per_query(configs, rounds, [&](size_t c) { return collide(env_pairs, env_cc, c); });
  double ed = env_pairs.empty() ? 0 : per_query(configs, rounds, [&](size_t c) { return distance(env_pairs, env_cd, c); });
  std::printf("{\"configs\":%zu,\"self_colliding_configs\":%zu,\"self_pairs\":%zu,\"environment_pairs\":%zu,"
              "\"self_collision_ns\":%.1f,\"self_distance_ns\":%.1f,\"environment_ns\":%.1f,\"environment_distance_ns\":%.1f}\n",
              configs, self_colliding, self_pairs.size(), env_pairs.size(), sc, sd, ec, ed);
  return 0;
}
