#include "tools/encode_run.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>
#include <utility>

#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

std::string MetaDataSource(const trainer::TrainOptions& o) {
  const std::string source = trainer::DataSource(o);
  if (o.meta_data_path || o.procedural_scene != trainer::ProceduralScene::kNone) return source;
  // The folder's own name: "../data/chair/" and "." (run inside chair/) both give "chair".
  std::error_code error;
  std::filesystem::path p = std::filesystem::absolute(source, error).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return error ? std::string() : p.filename().string();
}

encoder::EncodeOptions TrainedRunEncodeOptions(const trainer::TrainOptions& o,
                                               const trainer::RateState& rate, int iterations,
                                               float final_lambda_e) {
  encoder::EncodeOptions eo = trainer::RunEncodeOptions(o, rate);
  eo.metadata_json = nlohmann::json{
      {"encoder", "ecrf"},
      {"data", MetaDataSource(o)},
      {"preset", trainer::NameOf(o.preset)},
      {"iterations", iterations},
      {"lambda_e", final_lambda_e},
      {"alpha", o.alpha}}.dump();
  return eo;
}

EncodedRun EncodeRun(const trainer::TensorfModel& model, const encoder::EncodeOptions& options,
                     size_t target_bytes) {
  EncodedRun e;
  if (target_bytes > 0) {
    encoder::TargetSizeResult t = trainer::EncodeToTargetSize(model, options, target_bytes);
    e.bytes = std::move(t.bytes);
    e.report = t.report;
    e.step_scale = t.step_scale;
    e.encodes = t.encodes;
  } else {
    e.bytes = trainer::EncodeScene(model, options, &e.report);
  }
  return e;
}

}  // namespace tools
}  // namespace ecrf
