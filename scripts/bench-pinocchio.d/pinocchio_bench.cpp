// Pinocchio's side of scripts/bench-pinocchio: times fk, jacobian, rnea, nle, gravity, crba,
// aba and the derivatives of RNEA and ABA (computeRNEADerivatives: dtau/dq, dtau/dv, M;
// computeABADerivatives: dqdd/dq, dqdd/dv, Minv) on the states of a states file (written by gen_states.py) exactly as `rl model bench`
// times rl-core: per algorithm, enough repetitions over all states for ~2 ms per round, the
// median of `rounds` rounds, in ns per call. Prints one JSON line with the same keys.
//
// Usage: pinocchio_bench MODEL STATES FRAME [--floating-base] [--rounds N]
//
// MODEL is the Pinocchio model of the benchmark's URDF in Pinocchio's own text serialization
// (Model::saveToText), written by gen_states.py with the Python `pin` of the same release: the
// URDF parser runs there, not here. Compiled header-only (no PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION),
// so the algorithms and the model's loading are instantiated here with this program's flags
// (-O3 -DNDEBUG, the script's -march) and no Model crosses into a library built with other
// flags (with -march=native the precompiled URDF parser's Model crashed in ~ModelTpl, even at
// Eigen's 16-byte alignment); only Boost.Serialization's archive classes come from a library.
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>

#include <algorithm>
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

struct States {
  std::vector<std::string> joints;  // joint names, Pinocchio order (root_joint first if any)
  std::vector<Eigen::VectorXd> q, v, a;
};

// The states file: "rl-bench-states 1", "nq NQ nv NV joints J states S", J lines
// "joint NAME NQ NV", S lines "state q... v... a...".
States read_states(const std::string &path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open states file " + path);
  std::string magic, k1, k2, k3, k4;
  int version = 0, nq = 0, nv = 0, nj = 0, ns = 0;
  in >> magic >> version;
  if (magic != "rl-bench-states" || version != 1)
    throw std::runtime_error(path + ": not an rl-bench-states 1 file");
  in >> k1 >> nq >> k2 >> nv >> k3 >> nj >> k4 >> ns;
  if (!in || k1 != "nq" || k2 != "nv" || k3 != "joints" || k4 != "states")
    throw std::runtime_error(path + ": bad header line");
  States s;
  for (int j = 0; j < nj; ++j) {
    std::string kw, name;
    int jq, jv;
    in >> kw >> name >> jq >> jv;
    if (!in || kw != "joint") throw std::runtime_error(path + ": bad joint line");
    s.joints.push_back(name);
  }
  for (int i = 0; i < ns; ++i) {
    std::string kw;
    in >> kw;
    if (kw != "state") throw std::runtime_error(path + ": bad state line");
    Eigen::VectorXd q(nq), v(nv), a(nv);
    for (int k = 0; k < nq; ++k) in >> q[k];
    for (int k = 0; k < nv; ++k) in >> v[k];
    for (int k = 0; k < nv; ++k) in >> a[k];
    if (!in) throw std::runtime_error(path + ": short state line");
    s.q.push_back(q);
    s.v.push_back(v);
    s.a.push_back(a);
  }
  return s;
}

// Keeps a value alive for the optimiser (as Rust's std::hint::black_box).
template <typename T>
inline void keep(const T &x) {
  asm volatile("" : : "g"(&x) : "memory");
}

// Median ns per call of f(state) over all states, over `rounds` rounds: the same method as
// `rl model bench` (time_per_call in src/cli/model.rs).
template <typename F>
double time_per_call(std::size_t states, int rounds, F &&f) {
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
  // A benchmark of a debug build measures the assertions, not Pinocchio.
  std::fprintf(stderr, "pinocchio_bench: built without -DNDEBUG (a debug build): refusing to time\n");
  return 1;
#endif
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: %s MODEL STATES FRAME [--floating-base] [--rounds N]\n", argv[0]);
    return 2;
  }
  const std::string model_path = argv[1], states_path = argv[2], frame = argv[3];
  bool floating = false;
  int rounds = 15;
  for (int i = 4; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--floating-base") {
      floating = true;
    } else if (arg == "--rounds" && i + 1 < argc) {
      rounds = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  try {
    pin::Model model;
    model.loadFromText(model_path);
    // --floating-base says what the model must be: a free-flyer first joint or none.
    const bool has_free_flyer =
        model.njoints > 1 && model.joints[1].shortname() == "JointModelFreeFlyer";
    if (has_free_flyer != floating)
      throw std::runtime_error(model_path + (floating ? ": no free-flyer base, --floating-base given"
                                                      : ": a free-flyer base, --floating-base not given"));
    model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.80665));
    const States st = read_states(states_path);
    // The states are in Pinocchio's joint order: check it is this model's.
    std::vector<std::string> names(model.names.begin() + 1, model.names.end());
    if (names != st.joints) throw std::runtime_error("joint names of the states file differ from the model's");
    if (st.q.empty() || st.q[0].size() != model.nq || st.v[0].size() != model.nv)
      throw std::runtime_error("state sizes differ from the model's nq/nv");
    if (!model.existFrame(frame)) throw std::runtime_error("no frame named " + frame);
    const pin::FrameIndex fid = model.getFrameId(frame);
    pin::Data data(model);
    const std::size_t n = st.q.size();

    // τ for ABA: RNEA of the states' accelerations (as rl model bench does).
    // rnea_check: Σ τ over states and one-DoF joints (see `rl model bench --states-file`).
    std::vector<Eigen::VectorXd> tau(n);
    double check = 0.0;
    for (std::size_t s = 0; s < n; ++s) {
      tau[s] = pin::rnea(model, data, st.q[s], st.v[s], st.a[s]);
      for (pin::JointIndex j = 1; j < model.joints.size(); ++j)
        if (model.joints[j].nv() == 1) check += tau[s][model.joints[j].idx_v()];
    }

    Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, model.nv);
    J.setZero();
    double ns[9];
    ns[0] = time_per_call(n, rounds, [&](std::size_t s) {
      pin::forwardKinematics(model, data, st.q[s]);
      keep(data.oMi.back());
    });
    ns[1] = time_per_call(n, rounds, [&](std::size_t s) {
      pin::computeFrameJacobian(model, data, st.q[s], fid, pin::LOCAL_WORLD_ALIGNED, J);
      keep(J);
    });
    ns[2] = time_per_call(n, rounds, [&](std::size_t s) {
      keep(pin::rnea(model, data, st.q[s], st.v[s], st.a[s])[0]);
    });
    ns[3] = time_per_call(n, rounds, [&](std::size_t s) {
      keep(pin::nonLinearEffects(model, data, st.q[s], st.v[s])[0]);
    });
    ns[4] = time_per_call(n, rounds, [&](std::size_t s) {
      keep(pin::computeGeneralizedGravity(model, data, st.q[s])[0]);
    });
    ns[5] = time_per_call(n, rounds, [&](std::size_t s) {
      keep(pin::crba(model, data, st.q[s])(0, 0));
    });
    ns[6] = time_per_call(n, rounds, [&](std::size_t s) {
      keep(pin::aba(model, data, st.q[s], st.v[s], tau[s])[0]);
    });
    ns[7] = time_per_call(n, rounds, [&](std::size_t s) {
      pin::computeRNEADerivatives(model, data, st.q[s], st.v[s], st.a[s]);
      keep(data.dtau_dq(0, 0));
    });
    ns[8] = time_per_call(n, rounds, [&](std::size_t s) {
      pin::computeABADerivatives(model, data, st.q[s], st.v[s], tau[s]);
      keep(data.ddq_dq(0, 0));
    });
    const char *keys[9] = {"fk", "jacobian", "rnea", "nle", "gravity", "crba", "aba", "drnea",
                           "daba"};
    std::printf("{");
    for (int k = 0; k < 9; ++k) std::printf("\"%s_ns\": %.1f, ", keys[k], ns[k]);
    std::printf("\"dof\": %d, \"tool\": \"%s\", \"rnea_check\": %.17g}\n", model.nv,
                frame.c_str(), check);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "pinocchio_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
