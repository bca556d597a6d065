// Ctrl-C and SIGTERM stop a run with a checkpoint that --resume continues exactly
// (trainer/train/stop_signal.h); --checkpoint-minutes writes checkpoints by the clock.
#include "trainer/train/stop_signal.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "tests/common/scoped_temp_dir.h"
#include "tests/common/tiny_run.h"
#include "trainer/train/train_options.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TrainOptions TinyRun() {
  TrainOptions o = testing_runs::TinyBuiltinRun(32, 16, 40);
  o.voxels_init = 16L * 16 * 16;
  o.voxels_final = 24L * 24 * 24;
  o.batch_rays = 256;
  o.mlp_hidden = 16;
  return o;
}

bool HandlerIsDefault(int signal) {
  struct sigaction now = {};
  sigaction(signal, nullptr, &now);
  return now.sa_handler == SIG_DFL;
}

void ExpectSameParameters(TensorfModel& a, TensorfModel& b) {
  const auto pa = a.NamedParameters(), pb = b.NamedParameters();
  ASSERT_EQ(pa.size(), pb.size());
  for (size_t k = 0; k < pa.size(); ++k) {
    ASSERT_EQ(pa[k].size, pb[k].size) << pa[k].name;
    EXPECT_EQ(std::memcmp(pa[k].data, pb[k].data, pa[k].size * sizeof(float)), 0) << pa[k].name;
  }
}

// A SIGTERM (a scheduler's warning) arriving while training: the run stops after the step it is
// in with a checkpoint of that step, the exception names the signal, and the resumed run ends
// with the uninterrupted run's model, bit for bit. The handler runs once: a second signal would
// end the process, and leaving the scope restores the previous handlers.
TEST(StopSignal, SigtermStopsWithACheckpointThatResumesBitForBit) {
  const TrainOptions o = TinyRun();
  const Dataset train = LoadTrainingViews(o, "train");
  const Dataset test = LoadTrainingViews(o, "test");
  const testing_util::ScopedTempDir tmp("ecrf_stop_signal");
  TrainOptions whole = o, parts = o;
  whole.out_dir = tmp.path() + "/whole";
  parts.out_dir = tmp.path() + "/parts";
  ASSERT_EQ(mkdir(whole.out_dir.c_str(), 0755), 0);
  ASSERT_EQ(mkdir(parts.out_dir.c_str(), 0755), 0);
  TensorfModel a(ConfigFor(o, train));
  Train(whole, train, test, &a, nullptr);

  ASSERT_TRUE(HandlerIsDefault(SIGTERM));
  TensorfModel b(ConfigFor(o, train));
  {
    const StopSignalScope scope;
    EXPECT_FALSE(HandlerIsDefault(SIGTERM));
    EXPECT_FALSE(HandlerIsDefault(SIGINT));
    ASSERT_EQ(raise(SIGTERM), 0);  // recorded, not fatal
    EXPECT_EQ(StopSignal(), SIGTERM);
    EXPECT_TRUE(HandlerIsDefault(SIGTERM));  // the next SIGTERM ends the process
    try {
      Train(parts, train, test, &b, nullptr);
      ADD_FAILURE() << "training went on after SIGTERM";
    } catch (const TrainingStopped& e) {
      EXPECT_EQ(e.signal(), SIGTERM);
      EXPECT_EQ(std::string(e.what()), "training interrupted (SIGTERM) after iteration 1 of 40; " +
                                           parts.out_dir + "/checkpoint.ckpt holds it");
    }
  }
  EXPECT_TRUE(HandlerIsDefault(SIGTERM));
  EXPECT_TRUE(HandlerIsDefault(SIGINT));
  TensorfModel restored(ConfigFor(o, train));
  EXPECT_EQ(LoadModelCheckpoint(parts.out_dir + "/checkpoint.ckpt", &restored), 1);

  parts.resume = true;
  TensorfModel c(ConfigFor(o, train));
  {
    const StopSignalScope scope;  // a new scope forgets the earlier signal
    EXPECT_EQ(StopSignal(), 0);
    Train(parts, train, test, &c, nullptr);
  }
  ExpectSameParameters(a, c);
}

// --checkpoint-minutes: a checkpoint once that much time has passed since the last, at any
// iteration; 0 writes none (here no --checkpoint-every either).
TEST(StopSignal, CheckpointMinutesWritesCheckpointsByTheClock) {
  TrainOptions o = TinyRun();
  o.stop_after = 7;
  const Dataset train = LoadTrainingViews(o, "train");
  const Dataset test = LoadTrainingViews(o, "test");
  const testing_util::ScopedTempDir tmp("ecrf_checkpoint_minutes");
  for (const float minutes : {0.f, 1e-9f}) {
    SCOPED_TRACE(minutes);
    o.checkpoint_minutes = minutes;
    o.out_dir = tmp.path() + (minutes > 0.f ? "/timed" : "/never");
    ASSERT_EQ(mkdir(o.out_dir.c_str(), 0755), 0);
    TensorfModel model(ConfigFor(o, train));
    EXPECT_THROW(Train(o, train, test, &model, nullptr), TrainingStopped);
    const std::string ckpt = o.out_dir + "/checkpoint.ckpt";
    if (minutes == 0.f) {
      EXPECT_FALSE(std::filesystem::exists(ckpt));
    } else {
      TensorfModel restored(ConfigFor(o, train));
      EXPECT_EQ(LoadModelCheckpoint(ckpt, &restored), 7);
    }
  }
  EXPECT_EQ(TrainOptions().checkpoint_minutes, 10.f);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
