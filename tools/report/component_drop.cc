#include "tools/report/component_drop.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <string>

#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/report/quant_sensitivity.h"
#include "tools/report/report.h"
#include "trainer/data/file_io.h"
#include "trainer/data/ray_set.h"
#include "trainer/model/volume_render.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

trainer::VmGrid& GridOf(trainer::TensorfModel* model, int grid) {
  return grid == 0 ? model->density() : model->appearance();
}

// Channel `component` of a channels-last tensor of `cells` cells and `rank` channels.
void SaveAndZero(float* data, size_t cells, int rank, int component, std::vector<float>* saved) {
  if (saved) saved->resize(cells);
  for (size_t i = 0; i < cells; ++i) {
    float& v = data[i * size_t(rank) + size_t(component)];
    if (saved) (*saved)[i] = v;
    v = 0.f;
  }
}

void Restore(float* data, size_t cells, int rank, int component, const std::vector<float>& saved) {
  for (size_t i = 0; i < cells; ++i) data[i * size_t(rank) + size_t(component)] = saved[i];
}

}  // namespace

void ZeroComponent(trainer::TensorfModel* model, int grid, int mode, int component) {
  trainer::VmGrid& g = GridOf(model, grid);
  const int rank = g.ranks()[mode];
  if (component < 0 || component >= rank) throw std::invalid_argument("no such component");
  SaveAndZero(g.plane(mode), g.plane_size(mode) / size_t(rank), rank, component, nullptr);
  SaveAndZero(g.line(mode), g.line_size(mode) / size_t(rank), rank, component, nullptr);
}

ComponentReport MeasureComponentCosts(const trainer::TensorfModel& trained,
                                      const encoder::EncodeOptions& options, double lambda_e, int n,
                                      const float* origins, const float* dirs, const float* rgb) {
  if (options.steps.size() != 12) throw std::invalid_argument("components: 12 steps expected");
  encoder::EncodeOptions o = options;
  o.drop_zero_components = true;  // a zeroed component leaves the stream
  ComponentReport report;
  report.lambda_e = lambda_e;
  report.bytes = trainer::EncodeScene(trained, o).size();
  trainer::TensorfModel decoded = DecodedModel(trained, o.steps, o.blocks, o.mlp_max_level);
  report.mse = trainer::RenderMse(decoded, n, origins, dirs, rgb);
  trainer::TensorfModel model = trained;
  std::vector<float> plane_kept, line_kept;
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) {
      const int rank = GridOf(&model, g).ranks()[m];
      for (int r = 0; r < rank; ++r) {
        ComponentCost c;
        c.grid = g;
        c.mode = m;
        c.component = r;
        // Bits: the encoder with the component zeroed in the trained model.
        trainer::VmGrid& tg = GridOf(&model, g);
        const size_t plane_cells = tg.plane_size(m) / size_t(rank);
        const size_t line_cells = tg.line_size(m) / size_t(rank);
        SaveAndZero(tg.plane(m), plane_cells, rank, r, &plane_kept);
        SaveAndZero(tg.line(m), line_cells, rank, r, &line_kept);
        c.saved_bytes = long(report.bytes) - long(trainer::EncodeScene(model, o).size());
        Restore(tg.plane(m), plane_cells, rank, r, plane_kept);
        Restore(tg.line(m), line_cells, rank, r, line_kept);
        // Distortion: the decoded model without the component's decoded channels.
        trainer::VmGrid& dg = GridOf(&decoded, g);
        SaveAndZero(dg.plane(m), plane_cells, rank, r, &plane_kept);
        SaveAndZero(dg.line(m), line_cells, rank, r, &line_kept);
        c.dmse = trainer::RenderMse(decoded, n, origins, dirs, rgb) - report.mse;
        Restore(dg.plane(m), plane_cells, rank, r, plane_kept);
        Restore(dg.line(m), line_cells, rank, r, line_kept);
        c.drop = c.saved_bytes > 0 && c.dmse < lambda_e * 8.0 * double(c.saved_bytes);
        report.components.push_back(c);
      }
    }
  }
  // Every drop at once, measured as a file: the encoder's bytes and the decoded model's MSE.
  trainer::TensorfModel reduced = trained;
  for (const ComponentCost& c : report.components) {
    if (!c.drop) continue;
    ZeroComponent(&reduced, c.grid, c.mode, c.component);
    ++report.dropped;
  }
  report.file_after = trainer::EncodeScene(reduced, o);
  report.bytes_after = report.file_after.size();
  report.mse_after = trainer::RenderMse(DecodedModel(reduced, o.steps, o.blocks, o.mlp_max_level),
                                        n, origins, dirs, rgb);
  return report;
}

int RunReportComponents(int argc, char** argv) {
  std::string run, json_path, out_path;
  int rays = 16384;
  uint64_t seed = 7;
  double lambda_e = -1.0;
  auto app = MakeCommand(
      "report components",
      "which components of a trained run are worth their bits: for each density and appearance "
      "component, the file bytes the encoder saves without it and the MSE the decoded model "
      "loses (training rays); components whose loss is below lambda_e x their bits are marked, "
      "and the file without all of them is measured");
  app->add_option("RUN", run, "a run directory (or its checkpoint.ckpt)")
      ->type_name("RUN_DIR")
      ->required();
  app->add_option("--rays", rays, "training rays rendered per measurement")
      ->check(CLI::Range(256, 1 << 22))
      ->capture_default_str();
  app->add_option("--seed", seed, "ray draw")->capture_default_str();
  app->add_option("--lambda-e", lambda_e,
                  "the MSE a bit is worth (default: the lambda_e the run ended with)")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--json", json_path, "also write the table as JSON")->type_name("FILE");
  app->add_option("-o,--out", out_path, "write the file without the marked components")
      ->type_name("FILE.ecrf");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;

  const TrainedRun t = LoadTrainedRun(run, rays, seed);
  if (lambda_e < 0.0) lambda_e = t.info.lambda_e;
  const ComponentReport r = MeasureComponentCosts(t.model, t.options, lambda_e, rays,
                                                  t.origins.data(), t.dirs.data(), t.rgb.data());

  std::printf("%s: %zu bytes; decoded model on %d training rays: MSE %.4g (%.2f dB); lambda_e %g\n",
              run.c_str(), r.bytes, rays, r.mse, -10.0 * std::log10(r.mse), lambda_e);
  std::printf("%-11s %4s %4s %10s %11s %11s %s\n", "grid", "mode", "r", "bytes", "dMSE",
              "lambda*bits", "");
  for (const ComponentCost& c : r.components) {
    std::printf("%-11s %4d %4d %10ld %11.3g %11.3g %s\n", c.grid ? "appearance" : "density", c.mode,
                c.component, c.saved_bytes, c.dmse, lambda_e * 8.0 * double(c.saved_bytes),
                c.drop ? "drop" : "");
  }
  const double db_after = -10.0 * std::log10(r.mse_after);
  std::printf(
      "without the %d marked components: %zu bytes (%+.2f%%), training-ray PSNR %.2f dB (%+.3f "
      "dB)\n",
      r.dropped, r.bytes_after, 100.0 * (double(r.bytes_after) / double(r.bytes) - 1.0), db_after,
      db_after + 10.0 * std::log10(r.mse));
  if (!out_path.empty()) {
    trainer::WriteFileAtomically(out_path, r.file_after);
    std::printf("wrote %s\n", out_path.c_str());
  }
  if (!json_path.empty()) {
    nlohmann::json j = {{"run", run},
                        {"rays", rays},
                        {"seed", seed},
                        {"lambda_e", lambda_e},
                        {"bytes", r.bytes},
                        {"mse", r.mse},
                        {"dropped", r.dropped},
                        {"bytes_after", r.bytes_after},
                        {"mse_after", r.mse_after}};
    for (const ComponentCost& c : r.components) {
      j["components"].push_back({{"grid", c.grid ? "appearance" : "density"},
                                 {"mode", c.mode},
                                 {"component", c.component},
                                 {"saved_bytes", c.saved_bytes},
                                 {"dmse", c.dmse},
                                 {"drop", c.drop}});
    }
    WriteTextFile(json_path, j.dump(2) + "\n");
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
