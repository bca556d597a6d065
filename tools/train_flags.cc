#include "tools/train_flags.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <type_traits>

#include "tools/cli_args.h"
#include "tools/train_field_text.h"
#include "trainer/data/dataset.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/train_options.h"
#include "trainer/train/train_schedule.h"

namespace ecrf {
namespace tools {
namespace {

// The flags that choose layers 1 and 2 of a command line: the last value of each (empty when
// absent), read by CLI11 before the other flags are declared, so that --help can show the
// defaults of that preset and rate point. The full parse that follows reports every error.
struct LayerFlags {
  std::string preset, scene, rate, lambda_e, target_size, data, downscale, scene_type;
};

LayerFlags ReadLayerFlags(const std::vector<std::string>& args) {
  CLI::App app;
  app.allow_extras();
  app.set_help_flag();
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  LayerFlags f;
  app.add_option("--preset", f.preset);
  app.add_option("--scene", f.scene);
  app.add_option("--rate", f.rate);
  app.add_option("--lambda-e", f.lambda_e);
  app.add_option("--target-size", f.target_size);
  app.add_option("--data", f.data);
  app.add_option("--downscale", f.downscale);
  app.add_option("--scene-type", f.scene_type);
  try {
    app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 takes it reversed
  } catch (const CLI::ParseError&) {
    // A malformed line: the full parse says what is wrong with it.
  }
  return f;
}

std::string FloatText(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

int FinalGridEdge(const trainer::TrainOptions& o) {
  return int(std::lround(std::cbrt(double(o.voxels_final))));
}

// The layout's kind as FitScene will see it (--scene-type forces the forward-facing model or
// another).
trainer::DataKind DataKindOf(const trainer::DatasetManifest& m, const std::string& scene_type) {
  std::vector<trainer::Camera> cameras;
  for (const trainer::ViewSource& v : m.views) cameras.push_back(v.camera);
  const trainer::SceneType type =
      scene_type.empty() ? trainer::SceneType::kAuto
                         : trainer::ChoiceFromName<trainer::SceneType>(scene_type, "--scene-type");
  if (trainer::ModelsForwardFacing(type, m.white_background, cameras)) {
    return trainer::DataKind::kForwardFacing;
  }
  return m.white_background && !m.estimated_poses ? trainer::DataKind::kObjectWithGivenCameras
                                                  : trainer::DataKind::kOther;
}

// The default preset of --data: the cameras and image sizes are read (headers only; a few
// milliseconds for 100 PNGs). A dataset that cannot be read keeps `fast`: loading it reports why.
trainer::PresetChoice DataPreset(const LayerFlags& f) {
  const long downscale = std::max(1L, std::strtol(f.downscale.c_str(), nullptr, 10));
  try {
    const trainer::DatasetManifest m =
        trainer::ReadDatasetManifest(f.data, "train", int(downscale));
    const int64_t pixels =
        trainer::LoadedPixels(m.views, trainer::ImageDownscale(m, int(downscale)));
    return trainer::PresetForData(pixels, DataKindOf(m, f.scene_type));
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

trainer::FieldInfo TrainFieldInfo(const std::string& key) {
  trainer::FieldInfo found;
  const trainer::TrainOptions o;
  trainer::ForEachTrainField(o, [&](const trainer::FieldInfo& info, const auto&) {
    if (key == info.key) found = info;
  });
  if (key != found.key) throw std::logic_error("no training setting named '" + key + "'");
  return found;
}

trainer::TrainOptions BaseTrainOptions(const std::vector<std::string>& args,
                                       std::string* preset_reason) {
  const LayerFlags f = ReadLayerFlags(args);
  trainer::TrainOptions o;
  if (!f.preset.empty()) {
    o = trainer::PresetOptions(f.preset);
  } else if (!f.scene.empty()) {
    o = trainer::PresetOptions(trainer::Preset::kTiny);  // every procedural scene is CI-sized
  } else {
    const trainer::PresetChoice choice = f.data.empty() ? trainer::PresetChoice{} : DataPreset(f);
    o = trainer::PresetOptions(choice.preset);
    if (preset_reason) *preset_reason = choice.reason;
  }
  if (!f.rate.empty()) {
    trainer::ApplyRatePoint(f.rate, &o);
  } else if (!f.lambda_e.empty() && std::strtod(f.lambda_e.c_str(), nullptr) == 0.0) {
    trainer::ApplyRatePoint(trainer::RatePoint::kNone, &o);  // --lambda-e 0: plain TensoRF
  } else if (f.target_size.empty()) {
    trainer::ApplyRatePoint(trainer::RatePoint::kMedium, &o);  // a compressor by default
  }
  return o;
}

namespace {

// What --help shows after a flag's placeholder: its range or its names.
template <class T>
std::string ValueDescription(const trainer::FieldInfo& info) {
  if constexpr (trainer::IsNamedChoice<T>::value) {
    std::string names;
    for (const std::string& n : trainer::TypedNames<T>()) names += (names.empty() ? "" : ",") + n;
    return "{" + names + "}";
  } else {
    const std::string limits = trainer::LimitsText(info.limits);
    if (limits.empty()) return "";
    if (info.text == trainer::FlagText::kAutoNumber) return "auto or " + limits;
    return limits[0] == '[' || limits[0] == '(' ? "in " + limits : limits;
  }
}

// One flag of the table on app: bool fields are switches bound to the field; the others keep
// their text in f->texts until FinishTrainFlags converts it (the validator converts it once
// during parsing, so that a bad value is a parse error with CLI11's usual line).
template <class T>
void AddFieldFlag(CLI::App* app, TrainFlags* f, const trainer::FieldInfo& info, T& field) {
  const char* group = trainer::kFlagGroupTitles[size_t(info.group)];
  if constexpr (std::is_same_v<T, bool>) {
    app->add_flag(info.flag, field, info.help)->group(group);
  } else {
    std::string& text = f->texts[info.key];
    CLI::Option* option = app->add_option(info.flag, text, info.help);
    option->check(CLI::Validator(
        [info](std::string& value) {
          try {
            T parsed{};
            ParseFieldText(info, value, &parsed);
          } catch (const std::invalid_argument& e) {
            return std::string(e.what());
          }
          return std::string();
        },
        ValueDescription<T>(info)));
    if (*info.value_name) option->type_name(info.value_name);
    if (info.text != trainer::FlagText::kSize || field != T{})
      option->default_str(FieldText(info, field));
    option->group(group);
  }
}

}  // namespace

void AddTrainFlags(CLI::App* app, TrainFlags* f) {
  trainer::TrainOptions& o = f->options;
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  // The table's flags, section by section.
  for (size_t group = 0; group < std::size(trainer::kFlagGroupTitles); ++group) {
    trainer::ForEachTrainField(o, [&](const trainer::FieldInfo& info, auto& field) {
      if (info.flag && size_t(info.group) == group) AddFieldFlag(app, f, info, field);
    });
  }
  // --ranks D,A: both component counts at once, each within its own field's limits.
  f->ranks = std::to_string(o.density_rank) + "," + std::to_string(o.appearance_rank);
  app->add_option("--ranks", f->ranks,
                  "density and appearance components per plane and line, each in " +
                      trainer::LimitsText(TrainFieldInfo("density_rank").limits))
      ->type_name("D,A")
      ->capture_default_str()
      ->group(trainer::kFlagGroupTitles[size_t(trainer::FlagGroup::kSchedule)]);
  AddThreadsFlag(app, &f->threads)
      ->group(trainer::kFlagGroupTitles[size_t(trainer::FlagGroup::kRun)]);
}

trainer::TrainOptions FinishTrainFlags(const CLI::App& app, TrainFlags* f) {
  trainer::TrainOptions& o = f->options;
  auto given = [&](const char* flag) { return app.count(flag) > 0; };
  trainer::ForEachTrainField(o, [&](const trainer::FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (!std::is_same_v<T, bool>) {
      if (info.flag && given(info.flag)) ParseFieldText(info, f->texts.at(info.key), &field);
    }
  });
  if (given("--ranks")) {
    const size_t comma = f->ranks.find(',');
    if (comma == std::string::npos)
      throw std::invalid_argument("--ranks: '" + f->ranks + "' is not D,A");
    trainer::FieldInfo density = TrainFieldInfo("density_rank");
    trainer::FieldInfo appearance = TrainFieldInfo("appearance_rank");
    density.flag = appearance.flag = "--ranks";
    ParseFieldText(density, f->ranks.substr(0, comma), &o.density_rank);
    ParseFieldText(appearance, f->ranks.substr(comma + 1), &o.appearance_rank);
  }
  // Upsampling never shrinks the grid.
  if (given("--final-grid")) o.voxels_init = std::min(o.voxels_init, o.voxels_final);

  // --target-size picks the settings the line did not give (a rate point counts as giving all).
  trainer::TargetSizeFlagsGiven settings_given;
  const bool rate = given("--rate");
  settings_given.step_scale = rate || given("--quant-step-scale");
  settings_given.mlp_levels = rate || given("--mlp-levels");
  settings_given.ranks = rate || given("--ranks");
  settings_given.schedule = rate || given("--final-grid") || given("--upsample-at");
  settings_given.rate_start = rate || given("--rate-start");
  settings_given.iters = rate || given("--iters");
  trainer::ApplyTargetSizeDefaults(&o, settings_given);
  // Stopping on purpose keeps the work: a checkpoint is written at the stop.
  if (o.stop_after > 0 && o.checkpoint_every == 0) o.checkpoint_every = o.stop_after;
  ApplyThreads(f->threads);
  return o;
}

int ParseTrainCommandLine(CLI::App* app, TrainFlags* flags, int argc, char** argv,
                          trainer::TrainOptions* options) {
  if (const int rc = ParseCommandLine(app, argc, argv); rc >= 0) return rc;
  try {
    *options = FinishTrainFlags(*app, flags);
  } catch (const std::invalid_argument& e) {
    return UsageError(*app, e.what());
  }
  return -1;
}

trainer::TrainOptions ResolveTrainOptions(const std::vector<std::string>& args) {
  auto app = MakeCommand("train", "train a model");
  TrainFlags flags;
  flags.options = BaseTrainOptions(args);
  AddTrainFlags(app.get(), &flags);
  app->add_option("-o,--out", flags.options.out_dir, "run directory");
  if (!ParseArguments(app.get(), args))
    throw std::invalid_argument("--help is not a configuration");
  return FinishTrainFlags(*app, &flags);
}

std::string DescribeSettings(const trainer::TrainOptions& o) {
  std::string s = std::string("preset ") + trainer::NameOf(o.preset) + ", rate point " +
                  trainer::NameOf(o.rate_point);
  if (o.target_bytes > 0) s += ", target " + std::to_string(o.target_bytes) + " B";
  s += "; lambda_e " + FloatText(o.lambda_e) + ", steps x" + FloatText(o.quant_step_scale) +
       (o.density_step_factor != 1.f
            ? " (density x" + FloatText(o.quant_step_scale * o.density_step_factor) + ")"
            : std::string()) +
       ", " +
       (o.mlp_levels > 0 ? std::to_string(o.mlp_levels) + " MLP levels"
                         : std::string("binary16 MLP")) +
       ", ranks " + std::to_string(o.density_rank) + "," + std::to_string(o.appearance_rank) +
       ", final grid " + std::to_string(FinalGridEdge(o)) + "^3";
  // The run's own milestones (the preset's scaled to --iters), as the schedule runs them.
  s += ", upsampling at " + JoinText(trainer::ScaledMilestones(o.upsample_iters, o), ",") + " of " +
       std::to_string(o.iters) + " iterations";
  if (trainer::UsesRateObjective(o)) {
    s += ", rate terms from iteration " + std::to_string(trainer::RateStartIteration(o));
  }
  return s;
}

}  // namespace tools
}  // namespace ecrf
