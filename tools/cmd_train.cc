// `ecrf train`: trains a TensoRF VM model on posed images or on the built-in scene.
#include <cstdio>
#include <string>
#include <vector>

#include "tools/commands.h"
#include "tools/train_run.h"
#include "trainer/trainer.h"

namespace ecrf {
namespace tools {

int RunTrain(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: ecrf train (--data DIR | --scene builtin|capture|forward) [options] -o RUN_DIR\n%s", kTrainFlagsUsage);
      return 0;
    }
  }
  std::vector<int> rest;
  trainer::TrainOptions o = TrainOptionsFromArgs(argc, argv, &rest, /*rate_point_by_default=*/true);
  for (size_t k = 0; k < rest.size(); ++k) {
    const std::string a = argv[rest[k]];
    if ((a == "-o" || a == "--out") && k + 1 < rest.size() && rest[k + 1] == rest[k] + 1) {
      o.out_dir = argv[rest[++k]];
    } else {
      std::fprintf(stderr, "ecrf train: unknown option '%s'\n\nusage: ecrf train (--data DIR | --scene builtin|capture|forward) "
                   "[options] -o RUN_DIR\n%s", a.c_str(), kTrainFlagsUsage);
      return 2;
    }
  }
  if (o.out_dir.empty()) {
    std::fprintf(stderr, "ecrf train: -o RUN_DIR is required\n");
    return 2;
  }
  try {
    TrainEncodeEvaluate(o);
  } catch (const trainer::TrainingStopped& e) {
    std::printf("%s; continue with the same command and --resume\n", e.what());
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
