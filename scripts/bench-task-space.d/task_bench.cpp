// Pinocchio's side of scripts/bench-task-space: the task-space law of rl-rs (rl_core::task::
// operational_impedance with Priority::OrientationFirst and a Repulsion, fed by rl-sg's
// CapsuleModel::nearest_contacts) written on Pinocchio 4.1, timed per whole cycle over the
// states of problem.txt (gen_problem.py), as rl-task-bench times rl-rs's.
//
// Usage: task_bench MODEL PROBLEM_TXT --rounds N --torques OUT.json
//
// MODEL: the Panda in Pinocchio's text serialization (written by gen_problem.py with the
// Python pin of the same release), loaded as scripts/bench-pinocchio.d/pinocchio_bench.cpp
// loads its models: header-only, compiled here with the script's flags, no precompiled parser.
//
// One cycle (the law, step by step, is the spec in scripts/bench-task-space's header):
//   dynamics: either pinocchio::computeAllTerms (oMi, v, a at q̈ = 0, world J, M, nle in one
//   pass, plus centroidal quantities nobody asked for), or three sweeps: forwardKinematics
//   (q, v, 0) for v and a, crba(WORLD) for oMi, J and M, nonLinearEffects for h. Both are
//   timed; the program reports each and the script takes the faster as Pinocchio's time.
//   Then the tool frame's pose, LOCAL_WORLD_ALIGNED Jacobian and classical acceleration,
//   M's sparse Cholesky (pinocchio::cholesky::decompose) and its solves for M⁻¹Jᵀ and
//   M⁻¹J_nᵀ; the capsules to the world from oMi, every capsule's nearest sphere, the K closest
//   capsules under the influence distance, each contact point's LOCAL_WORLD_ALIGNED Jacobian
//   (getFrameJacobian at the point), and the small dense algebra in fixed-size Eigen (7 DoF
//   known at compile time: Pinocchio's side gets that advantage, rl-rs's runs at a capacity).
// Prints one JSON line: {"ns_all_terms", "ns_sweeps", "contacts_mean", ...}; writes the torques
// of every state (each variant's, checked equal here to 1e-12) to OUT.json.
#include <pinocchio/algorithm/cholesky.hpp>
#include <pinocchio/algorithm/compute-all-terms.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace pin = pinocchio;

namespace {

constexpr int NV = 7;
constexpr int MAX_CAPSULES = 32;
constexpr int MAX_CONTACTS = 8;
using Vec = Eigen::Matrix<double, NV, 1>;
using Mat6N = Eigen::Matrix<double, 6, NV>;
using MatN6 = Eigen::Matrix<double, NV, 6>;
using MatN = Eigen::Matrix<double, NV, NV>;
using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using ArrC = Eigen::Array<double, MAX_CAPSULES, 1>;

struct Gains {
  double kp[6], zeta, max_pos, max_ori, kq, zeta_q, band, limit_k, eps_lin, eps_ang;
  double influence, margin, kb, damping, a_max;
  int max_contacts;
};

struct Capsule {
  std::string joint;
  pin::JointIndex jid = 0;
  Vec3 a, d;  // local end and axis (b − a), in the joint frame
  double radius = 0;
};

struct Sphere {
  Vec3 c;
  double r;
};

struct Problem {
  std::string tool;
  Gains g{};
  Vec3 target_p;
  Mat3 target_R;
  Vec posture;
  std::vector<Vec> q, v;
  std::vector<Capsule> caps;
  std::vector<Sphere> obs;
};

Problem read_problem(const std::string &path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::string kw, k1, k2, k3, k4;
  int version = 0, nv = 0, ns = 0, nc = 0, no = 0;
  in >> kw >> version;
  if (kw != "rl-task-bench-problem" || version != 1)
    throw std::runtime_error(path + ": not an rl-task-bench-problem 1 file");
  in >> k1 >> nv >> k2 >> ns >> k3 >> nc >> k4 >> no;
  if (!in || k1 != "nv" || k2 != "states" || k3 != "capsules" || k4 != "obstacles")
    throw std::runtime_error(path + ": bad header");
  if (nv != NV) throw std::runtime_error("this program is built for 7 DoF");
  if (nc > MAX_CAPSULES) throw std::runtime_error("too many capsules");
  Problem p;
  auto expect = [&](const char *what) {
    in >> kw;
    if (!in || kw != what) throw std::runtime_error(path + ": expected " + what + ", got " + kw);
  };
  expect("tool");
  in >> p.tool;
  expect("gains");
  Gains &g = p.g;
  for (double &k : g.kp) in >> k;
  double kmax = 0;
  in >> g.zeta >> g.max_pos >> g.max_ori >> g.kq >> g.zeta_q >> g.band >> g.limit_k >> g.eps_lin >>
      g.eps_ang >> g.influence >> g.margin >> g.kb >> g.damping >> g.a_max >> kmax;
  g.max_contacts = static_cast<int>(kmax);
  if (g.max_contacts > MAX_CONTACTS) throw std::runtime_error("max_contacts too large");
  expect("target");
  for (int i = 0; i < 3; ++i) in >> p.target_p[i];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) in >> p.target_R(r, c);
  expect("posture");
  for (int i = 0; i < NV; ++i) in >> p.posture[i];
  for (int s = 0; s < ns; ++s) {
    expect("state");
    Vec q, v;
    for (int i = 0; i < NV; ++i) in >> q[i];
    for (int i = 0; i < NV; ++i) in >> v[i];
    p.q.push_back(q);
    p.v.push_back(v);
  }
  for (int c = 0; c < nc; ++c) {
    expect("capsule");
    Capsule cap;
    Vec3 b;
    in >> cap.joint >> cap.a[0] >> cap.a[1] >> cap.a[2] >> b[0] >> b[1] >> b[2] >> cap.radius;
    cap.d = b - cap.a;
    p.caps.push_back(cap);
  }
  for (int o = 0; o < no; ++o) {
    expect("obstacle");
    Sphere s;
    in >> s.c[0] >> s.c[1] >> s.c[2] >> s.r;
    p.obs.push_back(s);
  }
  if (!in) throw std::runtime_error(path + ": short file");
  return p;
}

template <typename T>
inline void keep(const T &x) {
  asm volatile("" : : "g"(&x) : "memory");
}

// The bounded inverse of the k×k SPD block A with bound eps per row: W = ε^{-1/2}, B = W A W;
// B − I positive definite (Cholesky succeeds): Λ = W B⁻¹ W; else B = V diag(σ) Vᵀ and
// Λ = W V diag(1/max(σ, 1)) Vᵀ W.
template <int K>
Eigen::Matrix<double, K, K> bounded_inverse(const Eigen::Matrix<double, K, K> &A,
                                            const Eigen::Matrix<double, K, 1> &w) {
  using M = Eigen::Matrix<double, K, K>;
  const M B = w.asDiagonal() * A * w.asDiagonal();
  Eigen::LLT<M> shifted(B - M::Identity());
  if (shifted.info() == Eigen::Success) {
    Eigen::LLT<M> llt(B);
    if (llt.info() == Eigen::Success) {
      M inv = llt.solve(M::Identity());
      return w.asDiagonal() * inv * w.asDiagonal();
    }
  }
  Eigen::SelfAdjointEigenSolver<M> es(B);
  const Eigen::Matrix<double, K, 1> s = es.eigenvalues().cwiseMax(1.0).cwiseInverse();
  return w.asDiagonal() * (es.eigenvectors() * s.asDiagonal() * es.eigenvectors().transpose()) *
         w.asDiagonal();
}

Vec3 saturate(const Vec3 &v, double max) {
  const double l = v.norm();
  return (l > max && l > 0) ? Vec3(v * (max / l)) : v;
}

struct Contact {
  int capsule;
  double d;
  Vec3 x, c;  // closest axis point, sphere centre
};

enum class Variant { AllTerms, Sweeps };

struct Law {
  const pin::Model &model;
  pin::Data data;
  const Problem &P;
  pin::FrameIndex tool;
  Vec lower, upper;
  Eigen::Matrix<double, 6, 1> w6;  // ε^{-1/2} per row [lin; ang]
  Vec3 w_lin, w_ang;
  // workspace
  Mat6N J;
  Eigen::Matrix<double, 6, Eigen::Dynamic> Jp;
  // The world capsules (structure of arrays; a = end, d = axis), 1/(d·d), radii; per capsule
  // the nearest sphere's distance and index.
  ArrC ax, ay, az, dx, dy, dz, inv, rad, dist, of;
  int contacts_seen = 0;
  std::array<Contact, MAX_CONTACTS> best;
  int nbest = 0;

  Law(const pin::Model &m, const Problem &p, pin::FrameIndex fid)
      : model(m), data(m), P(p), tool(fid), Jp(6, m.nv) {
    lower = m.lowerPositionLimit;
    upper = m.upperPositionLimit;
    w_lin.setConstant(1.0 / std::sqrt(p.g.eps_lin));
    w_ang.setConstant(1.0 / std::sqrt(p.g.eps_ang));
    w6 << w_lin, w_ang;
    for (ArrC *x : {&ax, &ay, &az, &dx, &dy, &dz, &inv, &rad}) x->setZero();
    for (std::size_t i = 0; i < p.caps.size(); ++i) {
      const double dd = p.caps[i].d.squaredNorm();  // a rigid motion keeps it
      inv[i] = dd > 1e-24 ? 1.0 / dd : 0.0;
      rad[i] = p.caps[i].radius;
    }
    J.setZero();
    Jp.setZero();
  }

  // The capsules to the world from data.oMi, every capsule's nearest sphere, and the (up to K)
  // capsules nearest to theirs under the influence distance, nearest first, into best[..nbest].
  // The capsules are kept as a structure of fixed-size Eigen arrays (padded to MAX_CAPSULES
  // with points at the origin that are never reported), so that the pass over the capsules for
  // one sphere is Eigen's vectorised array code, square roots included (the same structure as
  // rl-sg's kernel; a scalar loop with std::sqrt does not vectorise without -fno-math-errno).
  void nearest() {
    const Gains &g = P.g;
    const int nc = static_cast<int>(P.caps.size());
    for (int i = 0; i < nc; ++i) {
      const pin::SE3 &X = data.oMi[P.caps[i].jid];
      const Vec3 a = X.act(P.caps[i].a), d = X.rotation() * P.caps[i].d;
      ax[i] = a[0], ay[i] = a[1], az[i] = a[2];
      dx[i] = d[0], dy[i] = d[1], dz[i] = d[2];
    }
    dist.setConstant(INFINITY);
    of.setConstant(-1.0);
    for (std::size_t o = 0; o < P.obs.size(); ++o) {
      const Vec3 &c = P.obs[o].c;
      const ArrC px = c[0] - ax, py = c[1] - ay, pz = c[2] - az;
      const ArrC t = ((px * dx + py * dy + pz * dz) * inv).max(0.0).min(1.0);
      const ArrC ex = px - dx * t, ey = py - dy * t, ez = pz - dz * t;
      const ArrC d = (ex * ex + ey * ey + ez * ez).sqrt() - rad - P.obs[o].r;
      of = (d < dist).select(ArrC::Constant(static_cast<double>(o)), of);
      dist = dist.min(d);
    }
    // The K nearest capsules under the influence distance, nearest first.
    nbest = 0;
    const int K = g.max_contacts;
    for (int i = 0; i < nc; ++i) {
      const double bd = dist[i];
      if (of[i] < 0 || !(bd < g.influence)) continue;
      if (nbest == K && bd >= best[K - 1].d) continue;
      int at = nbest < K ? nbest++ : K - 1;
      while (at > 0 && best[at - 1].d > bd) {
        best[at] = best[at - 1];
        --at;
      }
      best[at] = Contact{i, bd, Vec3::Zero(), Vec3::Zero()};
    }
    // Their closest axis points and sphere centres.
    for (int k = 0; k < nbest; ++k) {
      const int i = best[k].capsule;
      const Vec3 &c = P.obs[static_cast<std::size_t>(of[i])].c;
      const Vec3 A(ax[i], ay[i], az[i]), D(dx[i], dy[i], dz[i]);
      const double t = std::clamp((c - A).dot(D) * inv[i], 0.0, 1.0);
      best[k].x = A + D * t;
      best[k].c = c;
    }
  }

  // The distance part alone, for the breakdown: forward kinematics and nearest().
  void distances_only(const Vec &q) {
    pin::forwardKinematics(model, data, q);
    nearest();
  }

  void run(Variant variant, const Vec &q, const Vec &v, Vec &tau) {
    const Gains &g = P.g;
    // --- rigid-body dynamics ---
    if (variant == Variant::AllTerms) {
      pin::computeAllTerms(model, data, q, v);  // oMi, v, a (q̈ = 0), J (world), M, nle
    } else {
      pin::forwardKinematics(model, data, q, v, Vec::Zero());    // v, a (q̈ = 0)
      pin::crba(model, data, q, pin::Convention::WORLD);          // oMi, J (world), M
      pin::nonLinearEffects(model, data, q, v);                   // nle
    }
    const pin::Frame &f = model.frames[tool];
    const pin::SE3 oMt = data.oMi[f.parentJoint] * f.placement;
    pin::getFrameJacobian(model, data, f.parentJoint, f.placement, pin::LOCAL_WORLD_ALIGNED, J);
    const Vec6 jdqd =
        pin::getFrameClassicalAcceleration(model, data, f.parentJoint, f.placement,
                                           pin::LOCAL_WORLD_ALIGNED)
            .toVector();
    MatN M = data.M;
    M.triangularView<Eigen::StrictlyLower>() = M.transpose();
    pin::cholesky::decompose(model, data);

    // --- 1. task acceleration ---
    const Vec6 xd = J * v;
    const Vec3 ep = saturate(P.target_p - oMt.translation(), g.max_pos);
    const Vec3 eo = saturate(pin::log3(Mat3(P.target_R * oMt.rotation().transpose())), g.max_ori);
    Vec6 e;
    e << ep, eo;
    Vec6 a;
    for (int r = 0; r < 6; ++r) {
      const double kd = 2.0 * g.zeta * std::sqrt(g.kp[r]);
      a[r] = kd * (0.0 - xd[r]) + g.kp[r] * e[r] - jdqd[r];
    }

    // --- 2. orientation first, then position ---
    MatN6 MinvJt = J.transpose();
    pin::cholesky::solve(model, data, MinvJt);
    const Mat6 Psi = J * MinvJt;
    const Mat3 Paa = Psi.bottomRightCorner<3, 3>(), Pll = Psi.topLeftCorner<3, 3>(),
               Pla = Psi.topRightCorner<3, 3>();
    const Mat3 L1 = bounded_inverse<3>(Paa, w_ang);
    const Mat3 L2 = bounded_inverse<3>(Mat3(Pll - Pla * L1 * Pla.transpose()), w_lin);
    const auto Ja = J.bottomRows<3>();
    const auto Jl = J.topRows<3>();
    const auto MinvJat = MinvJt.rightCols<3>();
    const Vec3 aa = a.tail<3>(), al = a.head<3>();
    const Vec3 F1 = L1 * aa;
    tau.noalias() = Ja.transpose() * F1;
    // The position yields to the nearest obstacle: its commanded acceleration (a_l + J̇q̇_l)
    // fades with the largest activation s = clamp((d_i − d)/(d_i − d_m), 0, 1) among the
    // contacts (rl-core's Repulsion::activation; NaN counts as 1); the −J̇q̇ compensation stays.
    nearest();
    double yielding = 0.0;
    for (int k = 0; k < nbest; ++k) {
      const double act = std::clamp((g.influence - best[k].d) / (g.influence - g.margin), 0.0, 1.0);
      yielding = std::max(yielding, std::isnan(act) ? 1.0 : act);
    }
    const Vec3 F2 = L2 * (al - yielding * (al + jdqd.head<3>()) - Pla * F1);
    // N1ᵀ x = x − J_aᵀ Λ1 (M⁻¹J_aᵀ)ᵀ x
    auto n1t = [&](const Vec &x) -> Vec {
      return x - Ja.transpose() * (L1 * (MinvJat.transpose() * x));
    };
    tau += n1t(Jl.transpose() * F2);

    // --- 3. posture in the nullspace of both ---
    const double dq_gain = 2.0 * g.zeta_q * std::sqrt(g.kq);
    Vec a0;
    for (int k = 0; k < NV; ++k) {
      a0[k] = g.kq * (P.posture[k] - q[k]) - dq_gain * v[k];
      if (g.band > 0) {
        const double below = g.band - (q[k] - lower[k]);
        const double above = g.band - (upper[k] - q[k]);
        if (below > 0)
          a0[k] += g.limit_k * below;
        else if (above > 0)
          a0[k] -= g.limit_k * above;
      }
    }
    // N₁ᵀ, then level 2's in level 1's nullspace: z = N₁ᵀ τ₀; z − N₁ᵀ J_lᵀ Λ₂ (M⁻¹J_lᵀ)ᵀ z.
    const Vec z = n1t(M * a0);
    const auto MinvJlt = MinvJt.leftCols<3>();
    tau += z - n1t(Jl.transpose() * (L2 * (MinvJlt.transpose() * z)));

    // --- 4. repulsion (the contacts of nearest() above) ---
    contacts_seen += nbest;
    Vec tau_rep = Vec::Zero();
    const double span = g.influence - g.margin;
    for (int k = 0; k < nbest; ++k) {
      const Contact &c = best[k];
      const Capsule &cap = P.caps[c.capsule];
      const Vec3 n = (c.x - c.c).normalized();
      const Vec3 p = c.x - n * cap.radius;
      const pin::SE3 &X = data.oMi[cap.jid];
      const pin::SE3 at_p(Mat3::Identity(), X.actInv(p));
      // getFrameJacobian writes the columns of the joint's supports only.
      Jp.setZero();
      pin::getFrameJacobian(model, data, cap.jid, at_p, pin::LOCAL_WORLD_ALIGNED, Jp);
      const Vec Jn = Jp.topRows<3>().transpose() * n;
      const double ddot = Jn.dot(v);
      const double s = std::clamp((g.influence - c.d) / span, 0.0, 1.0);
      const double acc =
          std::min(g.kb * (1.0 / std::max(c.d - g.margin, 1e-3) - 1.0 / span) +
                       s * g.damping * std::max(-ddot, 0.0),
                   g.a_max);
      Vec x = Jn;
      pin::cholesky::solve(model, data, x);
      const double w = Jn.dot(x);
      tau_rep += Jn * (acc / std::max(w, g.eps_lin));
    }
    tau += n1t(tau_rep);

    // --- 5. ---
    tau += data.nle;
  }
};

template <typename F>
double time_per_cycle(std::size_t states, int rounds, F &&f) {
  using clock = std::chrono::steady_clock;
  auto start = clock::now();
  for (std::size_t s = 0; s < states; ++s) f(s);
  double once = std::max(std::chrono::duration<double>(clock::now() - start).count(), 1e-9);
  std::size_t reps = std::min<std::size_t>(
      10000, std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(2e-3 / once))));
  std::vector<double> samples;
  for (int r = 0; r < rounds; ++r) {
    auto t = clock::now();
    for (std::size_t k = 0; k < reps; ++k)
      for (std::size_t s = 0; s < states; ++s) f(s);
    samples.push_back(std::chrono::duration<double>(clock::now() - t).count() * 1e9 /
                      static_cast<double>(reps * states));
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

}  // namespace

int main(int argc, char **argv) {
#ifndef NDEBUG
  std::fprintf(stderr, "task_bench: built without -DNDEBUG (a debug build): refusing to time\n");
  return 1;
#endif
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s MODEL PROBLEM_TXT [--rounds N] [--torques OUT.json]\n",
                 argv[0]);
    return 2;
  }
  const std::string model_path = argv[1], problem_path = argv[2];
  int rounds = 15;
  std::string torques_path;
  for (int i = 3; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--rounds" && i + 1 < argc)
      rounds = std::max(1, std::atoi(argv[++i]));
    else if (arg == "--torques" && i + 1 < argc)
      torques_path = argv[++i];
    else {
      std::fprintf(stderr, "unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  try {
    pin::Model model;
    model.loadFromText(model_path);
    model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.80665));
    if (model.nv != NV || model.nq != NV) throw std::runtime_error("not a 7-DoF model");
    Problem P = read_problem(problem_path);
    for (Capsule &c : P.caps) {
      if (!model.existJointName(c.joint)) throw std::runtime_error("no joint " + c.joint);
      c.jid = model.getJointId(c.joint);
    }
    if (!model.existFrame(P.tool)) throw std::runtime_error("no frame " + P.tool);
    const pin::FrameIndex fid = model.getFrameId(P.tool);
    const std::size_t n = P.q.size();

    Law law(model, P, fid);
    std::vector<Vec> tau_a(n), tau_b(n);
    for (std::size_t s = 0; s < n; ++s) law.run(Variant::AllTerms, P.q[s], P.v[s], tau_a[s]);
    const double contacts_mean = static_cast<double>(law.contacts_seen) / static_cast<double>(n);
    for (std::size_t s = 0; s < n; ++s) law.run(Variant::Sweeps, P.q[s], P.v[s], tau_b[s]);
    double worst = 0;
    for (std::size_t s = 0; s < n; ++s)
      worst = std::max(worst, (tau_a[s] - tau_b[s]).cwiseAbs().maxCoeff() / tau_a[s].norm());
    if (worst > 1e-12) {
      std::fprintf(stderr, "task_bench: the two Pinocchio variants disagree (%g)\n", worst);
      return 1;
    }
    Vec tau;
    const double ns_all = time_per_cycle(n, rounds, [&](std::size_t s) {
      law.run(Variant::AllTerms, P.q[s], P.v[s], tau);
      keep(tau);
    });
    const double ns_sweeps = time_per_cycle(n, rounds, [&](std::size_t s) {
      law.run(Variant::Sweeps, P.q[s], P.v[s], tau);
      keep(tau);
    });
    const double ns_dist = time_per_cycle(n, rounds, [&](std::size_t s) {
      law.distances_only(P.q[s]);
      keep(law.best);
    });
    if (!torques_path.empty()) {
      std::ofstream out(torques_path);
      out << "{\"tau\": [";
      char buf[64];
      for (std::size_t s = 0; s < n; ++s) {
        out << (s ? ",\n" : "\n") << "[";
        for (int k = 0; k < NV; ++k) {
          std::snprintf(buf, sizeof buf, "%.17g", tau_a[s][k]);
          out << (k ? ", " : "") << buf;
        }
        out << "]";
      }
      out << "]}\n";
    }
    std::printf(
        "{\"library\": \"pinocchio\", \"pinocchio_version\": \"%s\", \"states\": %zu, "
        "\"rounds\": %d, \"ns_all_terms\": %.3f, \"ns_sweeps\": %.3f, \"ns_distances\": %.3f, "
        "\"contacts_mean\": %.4f}\n",
        PINOCCHIO_VERSION, n, rounds, ns_all, ns_sweeps, ns_dist, contacts_mean);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "task_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
