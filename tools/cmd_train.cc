// `ecrf train`: trains a TensoRF VM model on posed images or on a procedural scene, then encodes,
// decodes and scores the file.
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/commands.h"
#include "tools/train_flags.h"
#include "tools/train_run.h"
#include "trainer/train/train_config.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

int RunTrain(int argc, char** argv) {
  auto app = MakeCommand(
      "train",
      "Trains a TensoRF VM model with the ECRF rate objective, encodes RUN_DIR/scene.ecrf, decodes "
      "it with the embeddable decoder and scores the decoded file.\n"
      "usage: ecrf train (--data DIR | --scene NAME) [options] -o RUN_DIR\n"
      "The defaults below are those of this command line's --preset and --rate.");
  TrainFlags flags;
  std::string preset_reason;
  flags.options = BaseTrainOptions(std::vector<std::string>(argv + 1, argv + argc), &preset_reason);
  AddTrainFlags(app.get(), &flags);
  bool print_config = false;
  app->add_option("-o,--out", flags.options.out_dir, "run directory (created with its parents)")
      ->type_name("RUN_DIR");
  app->add_flag("--print-config", print_config,
                "print the resolved configuration (config.json) and exit");
  trainer::TrainOptions o;
  if (const int rc = ParseTrainCommandLine(app.get(), &flags, argc, argv, &o); rc >= 0) return rc;
  if (print_config) {
    std::printf("%s\n", trainer::TrainConfigToJson(o).c_str());
    return 0;
  }
  if (o.out_dir.empty()) {
    std::fprintf(stderr, "ecrf train: error: -o RUN_DIR is required; see 'ecrf train --help'\n");
    return 2;
  }
  if (!preset_reason.empty()) std::printf("%s\n", preset_reason.c_str());
  try {
    TrainEncodeEvaluate(o);
  } catch (const trainer::TrainingStopped& e) {
    std::printf("%s; continue with the same command and --resume\n", e.what());
    // A run stopped by a signal exits as the shell reports one (130 for Ctrl-C, 143 SIGTERM).
    if (e.signal() != 0) return 128 + e.signal();
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
