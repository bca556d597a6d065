#include "tools/report/quant_sensitivity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>

#include "encoder/grid_dct.h"
#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/report/report.h"
#include "trainer/data/ray_set.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
trainer::TensorfModel DecodedModel(const trainer::TensorfModel& trained,
                                   const std::vector<float>& steps,
                                   const encoder::RateConfig& blocks, int mlp_max_level) {
  trainer::TensorfModel model = trained;
  trainer::VmGrid* grids[2] = {&model.density(), &model.appearance()};
  for (int g = 0; g < 2; ++g) {
    std::vector<float> q;
    trainer::ReconstructQuantizedGrid(*grids[g], steps.data() + 6 * g, blocks, &q);
    grids[g]->params() = std::move(q);
  }
  if (mlp_max_level > 0) {
    std::vector<float> head;
    trainer::ReconstructQuantizedHead(model, mlp_max_level, &head);
    model.head().params() = std::move(head);
  }
  return model;
}

TrainedRun LoadTrainedRun(const std::string& run, int rays, uint64_t seed) {
  const std::string ckpt = IsDirectory(run) ? run + "/checkpoint.ckpt" : run;
  trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(ckpt);
  if (!info.has_config)
    throw std::runtime_error(ckpt + ": no stored configuration (an older ecrf wrote it)");
  trainer::RateState rate;
  TrainedRun t{info, trainer::LoadModelFromCheckpoint(ckpt, &rate), {}, rays, {}, {}, {}};
  t.options = trainer::RunEncodeOptions(info.config, rate);
  if (!rate.active || t.options.steps.size() != 12)
    t.options.steps = trainer::ChooseQuantSteps(t.model, t.options.blocks, info.config.coef_bits);
  const trainer::Dataset data = trainer::LoadTrainingViews(info.config, "train");
  trainer::RaySet set(data.views);
  for (std::vector<float>* v : {&t.origins, &t.dirs, &t.rgb}) v->resize(size_t(rays) * 3);
  std::mt19937_64 rng(seed);
  set.NextBatch(rays, rng, t.origins.data(), t.dirs.data(), t.rgb.data());
  return t;
}

SensitivityReport MeasureQuantSensitivity(const trainer::TensorfModel& trained,
                                          const std::vector<float>& steps,
                                          const encoder::RateConfig& blocks, int mlp_max_level,
                                          int n, const float* origins, const float* dirs,
                                          const float* rgb, uint64_t seed, double noise_scale) {
  if (steps.size() != 12) throw std::invalid_argument("sensitivity: 12 steps expected");
  // The decoded model: what the file renders.
  trainer::TensorfModel model = DecodedModel(trained, steps, blocks, mlp_max_level);
  trainer::VmGrid* grids[2] = {&model.density(), &model.appearance()};
  SensitivityReport report;
  report.rays = n;
  report.mse = trainer::RenderMse(model, n, origins, dirs, rgb);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(-0.5f, 0.5f);
  for (int t = 0; t < 12; ++t) {
    trainer::VmGrid& grid = *grids[t / 6];
    const encoder::GridBlockLayout layout = trainer::RateTensorLayout(grid, t % 6, blocks);
    float* data = t % 6 < 3 ? grid.plane(t % 6) : grid.line(t % 6 - 3);
    const std::vector<float> kept(data, data + layout.tensor_size());
    std::vector<float> coeffs(layout.num_coeffs()), noise(layout.num_coeffs(), 0.f);
    encoder::ForwardBlocks(data, layout, coeffs.data());
    TensorSensitivity s;
    s.name = encoder::RateTensorName(t);
    s.step = steps[t];
    double levels = 0.0;
    for (size_t i = 0; i < coeffs.size(); ++i) {
      // The reconstruction holds level * step up to the float rounding of the transforms.
      const double level = std::nearbyint(double(coeffs[i]) / s.step);
      if (level == 0.0) continue;
      ++s.nonzero;
      levels += std::fabs(level);
      noise[i] = static_cast<float>(unit(rng) * s.step * noise_scale);
    }
    if (s.nonzero > 0) {
      double added = 0.0;
      std::vector<float> moved(coeffs.size());
      for (const float sign : {1.f, -1.f}) {
        for (size_t i = 0; i < coeffs.size(); ++i) moved[i] = coeffs[i] + sign * noise[i];
        encoder::InverseBlocks(moved.data(), layout, data);
        added += trainer::RenderMse(model, n, origins, dirs, rgb) - report.mse;
      }
      std::copy(kept.begin(), kept.end(), data);
      s.dmse = added / 2.0;
      s.mean_abs_level = levels / static_cast<double>(s.nonzero);
      s.slope = s.dmse / static_cast<double>(s.nonzero);
    }
    report.quant_mse += s.dmse;
    report.tensors.push_back(s);
  }
  // Equal slopes at the same rate: step_t^2 scales by g / slope_t, with g the n-weighted
  // geometric mean of the slopes (sum n_t log step_t, the rate, is unchanged); the D_t become
  // n_t g, their sum N g against N a today (a: the n-weighted arithmetic mean).
  double total = 0.0, log_sum = 0.0;
  for (const TensorSensitivity& s : report.tensors) {
    if (s.nonzero == 0 || !(s.slope > 0.0)) continue;
    total += static_cast<double>(s.nonzero);
    log_sum += static_cast<double>(s.nonzero) * std::log(s.slope);
  }
  if (total > 0.0) {
    const double geometric = std::exp(log_sum / total);
    for (TensorSensitivity& s : report.tensors) {
      s.balanced_step = s.step;
      if (s.nonzero == 0 || !(s.slope > 0.0)) {
        report.balanced_quant_mse += s.dmse;
        continue;
      }
      s.balanced_step = static_cast<float>(s.step * std::sqrt(geometric / s.slope));
      report.balanced_quant_mse += geometric * static_cast<double>(s.nonzero);
    }
  } else {
    report.balanced_quant_mse = report.quant_mse;
  }
  const double after = report.mse - (report.quant_mse - report.balanced_quant_mse);
  report.predicted_gain_db = after > 0.0 ? 10.0 * std::log10(report.mse / after) : 0.0;
  return report;
}

int RunReportSensitivity(int argc, char** argv) {
  std::string run, json_path;
  int rays = 32768;
  uint64_t seed = 7;
  auto app = MakeCommand(
      "report sensitivity",
      "where quantization costs PSNR in a trained run: for each coded tensor, the MSE that noise "
      "of its quantization step adds on its nonzero levels (on training rays, decoded model), "
      "and what allocating the steps by equal rate-distortion slopes would gain at the same rate");
  app->add_option("RUN", run, "a run directory (or its checkpoint.ckpt)")
      ->type_name("RUN_DIR")
      ->required();
  app->add_option("--rays", rays, "training rays rendered per measurement")
      ->check(CLI::Range(256, 1 << 22))
      ->capture_default_str();
  app->add_option("--seed", seed, "ray and noise draw")->capture_default_str();
  app->add_option("--json", json_path, "also write the table as JSON")->type_name("FILE");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;

  const TrainedRun t = LoadTrainedRun(run, rays, seed);
  const encoder::EncodeOptions& o = t.options;
  const SensitivityReport r =
      MeasureQuantSensitivity(t.model, o.steps, o.blocks, o.mlp_max_level, rays, t.origins.data(),
                              t.dirs.data(), t.rgb.data(), seed);

  std::printf("%s: decoded model on %d training rays: MSE %.4g (%.2f dB)\n", run.c_str(), rays,
              r.mse, -10.0 * std::log10(r.mse));
  std::printf("%-20s %9s %9s %8s %11s %11s %9s\n", "tensor", "step", "nonzero", "mean|l|",
              "D_t (MSE)", "D_t/nonzero", "balanced");
  for (const TensorSensitivity& s : r.tensors) {
    std::printf("%-20s %9.4g %9ld %8.2f %11.3g %11.3g %9.4g\n", s.name.c_str(), s.step, s.nonzero,
                s.mean_abs_level, s.dmse, s.slope, s.balanced_step);
  }
  std::printf(
      "quantization noise of the nonzero levels: %.3g MSE, %.1f%% of the decoded model's; with "
      "the balanced steps (same rate, high-rate model) %.3g: %+.3f dB predicted\n",
      r.quant_mse, 100.0 * r.quant_mse / r.mse, r.balanced_quant_mse, r.predicted_gain_db);
  if (!json_path.empty()) {
    nlohmann::json j = {{"run", run},
                        {"rays", rays},
                        {"seed", seed},
                        {"mse", r.mse},
                        {"quant_mse", r.quant_mse},
                        {"balanced_quant_mse", r.balanced_quant_mse},
                        {"predicted_gain_db", r.predicted_gain_db}};
    for (const TensorSensitivity& s : r.tensors) {
      j["tensors"].push_back({{"name", s.name},
                              {"step", s.step},
                              {"nonzero", s.nonzero},
                              {"mean_abs_level", s.mean_abs_level},
                              {"dmse", s.dmse},
                              {"slope", s.slope},
                              {"balanced_step", s.balanced_step}});
    }
    WriteTextFile(json_path, j.dump(2) + "\n");
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
