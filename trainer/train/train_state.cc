#include "trainer/train/train_state.h"

#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace ecrf {
namespace trainer {
namespace {

void SaveAdam(const std::string& name, const Adam& adam, Checkpoint* ck, nlohmann::json* j) {
  ck->arrays.push_back(
      {"adam." + name + ".m", {int64_t(adam.first_moment().size())}, adam.first_moment()});
  ck->arrays.push_back(
      {"adam." + name + ".v", {int64_t(adam.second_moment().size())}, adam.second_moment()});
  (*j)["adam_steps"][name] = adam.step_count();
}

void LoadAdam(const std::string& name, const Checkpoint& ck, const nlohmann::json& j,
              const std::string& path, size_t size, Adam* adam) {
  const CheckpointArray* m = ck.Find("adam." + name + ".m");
  const CheckpointArray* v = ck.Find("adam." + name + ".v");
  if (!m || !v || m->data.size() != size || v->data.size() != size) {
    throw std::runtime_error(path + ": training state: optimizer '" + name +
                             "' is missing or of the wrong size");
  }
  adam->Reset(size);
  adam->first_moment() = m->data;
  adam->second_moment() = v->data;
  adam->set_step_count(j.at("adam_steps").at(name).get<long>());
}

}  // namespace

void Optimizers::Reset(TensorfModel& m) {
  density.Reset(m.density().params().size());
  appearance.Reset(m.appearance().params().size());
  head.Reset(m.head().params().size());
  lr_scale = 1.0f;  // TensoRF's lr_upsample_reset: back to the initial rates
}

void Optimizers::Step(TensorfModel& m, const TrainOptions& o) {
  const float lr_grid = o.lr_grid * lr_scale, lr_net = o.lr_network * lr_scale;
  density.Step(m.density().params().data(), m.density().grads().data(), m.density().params().size(),
               lr_grid);
  appearance.Step(m.appearance().params().data(), m.appearance().grads().data(),
                  m.appearance().params().size(), lr_grid);
  head.Step(m.head().params().data(), m.head().grads().data(), m.head().params().size(), lr_net);
}

Checkpoint SaveTrainState(const Optimizers& opt, const RateState& rate, const RaySet& rays,
                          const TrainProgress& progress) {
  Checkpoint ck;
  nlohmann::json j;
  SaveAdam("density", opt.density, &ck, &j);
  SaveAdam("appearance", opt.appearance, &ck, &j);
  SaveAdam("head", opt.head, &ck, &j);
  if (rate.active) SaveAdam("entropy", rate.adam, &ck, &j);
  j["lr_scale"] = opt.lr_scale;  // a float is exact as a JSON double
  j["l1_weight"] = progress.l1_weight;
  j["train_seconds"] = progress.train_seconds;
  j["psnr_curve"] = progress.psnr_curve;
  std::ostringstream rng;
  rng << progress.rng;
  j["rng"] = rng.str();
  CheckpointArray keep{"rays.keep16", {}, {}};
  std::string shuffle_rng;
  uint64_t cursor = 0;
  rays.SaveState(&keep.data, &shuffle_rng, &cursor);
  keep.shape = {int64_t(keep.data.size())};
  ck.arrays.push_back(std::move(keep));
  j["rays_shuffle_rng"] = shuffle_rng;
  j["rays_cursor"] = cursor;
  if (progress.exposure.enabled()) {
    const std::vector<float>& g = progress.exposure.log_gain();
    ck.arrays.push_back({"exposure.log_gain", {int64_t(g.size() / 3), 3}, g});
    SaveAdam("exposure", progress.exposure.adam(), &ck, &j);
  }
  // Doubles survive JSON exactly, so a resumed run refines from the same cameras.
  for (const Camera& c : progress.cameras) {
    nlohmann::json cam = {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2};
    for (const auto& row : c.c2w) {
      for (double x : row) cam.push_back(x);
    }
    j["cameras"].push_back(cam);
  }
  ck.json = j.dump();
  return ck;
}

bool LoadTrainState(const Checkpoint& ck, const std::string& path, Optimizers* opt, RateState* rate,
                    RaySet* rays, TrainProgress* progress) {
  nlohmann::json all;
  try {
    all = nlohmann::json::parse(ck.json);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": checkpoint metadata: " + e.what());
  }
  if (!all.contains("train_state")) return false;
  const nlohmann::json& j = all["train_state"];
  try {
    LoadAdam("density", ck, j, path, opt->density.size(), &opt->density);
    LoadAdam("appearance", ck, j, path, opt->appearance.size(), &opt->appearance);
    LoadAdam("head", ck, j, path, opt->head.size(), &opt->head);
    if (rate->active) LoadAdam("entropy", ck, j, path, rate->entropy.params().size(), &rate->adam);
    opt->lr_scale = j.at("lr_scale").get<float>();
    progress->l1_weight = j.at("l1_weight").get<float>();
    progress->train_seconds = j.at("train_seconds").get<double>();
    progress->psnr_curve = j.at("psnr_curve").get<std::vector<std::pair<double, double>>>();
    std::istringstream rng(j.at("rng").get<std::string>());
    rng >> progress->rng;
    if (rng.fail())
      throw std::runtime_error(path + ": training state: damaged random generator state");
    if (progress->exposure.enabled()) {
      // The codes were reset to the training views before the state is loaded.
      const CheckpointArray* g = ck.Find("exposure.log_gain");
      if (!g || g->data.size() != progress->exposure.log_gain().size()) {
        throw std::runtime_error(path +
                                 ": training state: the exposure codes are missing or for other "
                                 "views (was the checkpoint written with --exposure-codes off?)");
      }
      progress->exposure.log_gain() = g->data;
      LoadAdam("exposure", ck, j, path, g->data.size(), &progress->exposure.adam());
    }
    if (!progress->cameras.empty()) {
      // The cameras were set to the training views' before the state is loaded.
      if (!j.contains("cameras") || j["cameras"].size() != progress->cameras.size()) {
        throw std::runtime_error(path +
                                 ": training state: the refined cameras are missing or for other "
                                 "views (was the checkpoint written with --refine-cameras off?)");
      }
      for (size_t v = 0; v < progress->cameras.size(); ++v) {
        const std::vector<double> cam = j["cameras"][v].get<std::vector<double>>();
        if (cam.size() != 20) throw std::runtime_error(path + ": training state: damaged camera");
        Camera& c = progress->cameras[v];
        double* lens[8] = {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2, &c.p1, &c.p2};
        for (int k = 0; k < 8; ++k) *lens[k] = cam[size_t(k)];
        for (int k = 0; k < 12; ++k) c.c2w[k / 4][k % 4] = cam[size_t(8 + k)];
      }
    }
    const CheckpointArray* keep = ck.Find("rays.keep16");
    if (!keep) throw std::runtime_error(path + ": training state: the kept-ray set is missing");
    try {
      rays->RestoreState(keep->data, j.at("rays_shuffle_rng").get<std::string>(),
                         j.at("rays_cursor").get<uint64_t>());
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": training state: " + e.what());
  }
  return true;
}

}  // namespace trainer
}  // namespace ecrf
