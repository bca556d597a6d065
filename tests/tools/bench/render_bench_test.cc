#include "tools/bench/render_bench.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "decoder/mlp_gemm.h"
#include "tests/common/invoke.h"
#include "tools/commands.h"

namespace ecrf {
namespace tools {
namespace {

TEST(RenderBenchTest, BlobSceneRendersSamplesAndColours) {
  dec::SceneField s;
  const Status st = MakeBlobScene(24, dec::GridStorage::kInt16, true, 1, &s);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_TRUE(s.has_mask);
  RenderBenchResult r;
  ASSERT_TRUE(BenchmarkRender(s, 32, 32, 2, 2, dec::RenderOptions(), &r).ok());
  EXPECT_EQ(r.threads, 2);
  EXPECT_EQ(r.views, 2);
  EXPECT_GT(r.samples_per_view, 0u);
  EXPECT_GT(r.color_samples_per_view, 0u);
  EXPECT_LE(r.color_samples_per_view, r.samples_per_view);
}

TEST(RenderBenchTest, RefusesBadArguments) {
  dec::SceneField s;
  EXPECT_FALSE(MakeBlobScene(1, dec::GridStorage::kFloat32, false, 1, &s).ok());
  RenderBenchResult r;
  EXPECT_FALSE(BenchmarkRender(s, 0, 32, 1, 1, dec::RenderOptions(), &r).ok());
}

// `ecrf bench render` end to end: one figure set per thread count, written as JSON.
TEST(RenderBenchTest, CommandWritesItsFiguresAsJson) {
  const std::string json = ::testing::TempDir() + "/bench_render.json";
  std::remove(json.c_str());
  EXPECT_EQ(testing_cli::Invoke(
                RunEcrf, {"ecrf", "bench", "render", "--res", "16", "--width", "24", "--height",
                          "16", "--views", "1", "--threads", "1,2", "--json", json}),
            0);
  std::ifstream in(json);
  ASSERT_TRUE(in) << json;
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* t : {"threads_1", "threads_2"}) {
    EXPECT_GT(j.at(std::string(t) + ".ms_per_view").get<double>(), 0.0) << t;
    EXPECT_GT(j.at(std::string(t) + ".samples_per_view").get<double>(), 0.0) << t;
  }
  // The renderer's output does not depend on the thread count, nor its work.
  EXPECT_EQ(j.at("threads_1.samples_per_view"), j.at("threads_2.samples_per_view"));
}

// --kernels all: one figure set per MLP kernel this CPU runs, all with the portable kernel's
// pixels (the command fails when a kernel's image differs); an unknown or unavailable kernel is a
// usage error.
TEST(RenderBenchTest, EveryMlpKernelIsTimedAndRendersThePortablePixels) {
  const std::string json = ::testing::TempDir() + "/bench_render_kernels.json";
  std::remove(json.c_str());
  EXPECT_EQ(testing_cli::Invoke(RunEcrf, {"ecrf", "bench", "render", "--res", "16", "--width", "24",
                                          "--height", "16", "--views", "1", "--threads", "1",
                                          "--kernels", "all", "--json", json}),
            0);
  std::ifstream in(json);
  ASSERT_TRUE(in) << json;
  const nlohmann::json j = nlohmann::json::parse(in);
  int kernels = 0;
  for (const dec::GemmKernel k :
       {dec::GemmKernel::kPortable, dec::GemmKernel::kAvx2, dec::GemmKernel::kAvx512}) {
    const std::string key = std::string(dec::GemmKernelName(k)) + ".threads_1.samples_per_view";
    EXPECT_EQ(j.contains(key), dec::GemmKernelAvailable(k)) << key;
    kernels += j.contains(key);
  }
  EXPECT_EQ(j.size(), 5u * kernels);
  EXPECT_EQ(testing_cli::Invoke(
                RunEcrf, {"ecrf", "bench", "render", "--res", "16", "--kernels", "portable,sse9"}),
            2);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
