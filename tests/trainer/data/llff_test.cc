#include "trainer/data/llff.h"
#include "tests/common/error_of.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/data/npy.h"

namespace ecrf::trainer {
namespace {

using testing_errors::Contains;
using testing_errors::ErrorOf;

namespace fs = std::filesystem;

constexpr int kImages = 10;
constexpr double kHeight = 48, kWidth = 64, kFocal = 50;  // hwf of the full-size capture

// np.save's layout: magic, version, header length, a dict literal padded to 64 bytes.
std::vector<uint8_t> NpyBytes(const std::vector<double>& values, const std::string& shape,
                              const std::string& descr = "<f8", int version = 1) {
  std::string header =
      "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
  const size_t prefix = version == 1 ? 10 : 12;
  while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::vector<uint8_t> bytes = {0x93, 'N', 'U', 'M', 'P', 'Y', uint8_t(version), 0};
  const size_t n = header.size();
  bytes.push_back(uint8_t(n));
  bytes.push_back(uint8_t(n >> 8));
  if (version != 1) {
    bytes.push_back(uint8_t(n >> 16));
    bytes.push_back(uint8_t(n >> 24));
  }
  bytes.insert(bytes.end(), header.begin(), header.end());
  for (double v : values) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    for (int b = 0; b < 8; ++b) bytes.push_back(uint8_t(bits >> (8 * b)));
  }
  return bytes;
}

// A row of poses_bounds.npy for an OpenGL camera-to-world [x | y | z | t]: LLFF stores the
// columns [down, right, back] = [-y, x, z].
std::vector<double> LlffRow(const double gl[3][4], double near, double far) {
  std::vector<double> row;
  for (int r = 0; r < 3; ++r) {
    for (double v : {-gl[r][1], gl[r][0], gl[r][2], gl[r][3],
                     r == 0   ? kHeight
                     : r == 1 ? kWidth
                              : kFocal}) {
      row.push_back(v);
    }
  }
  row.push_back(near);
  row.push_back(far);
  return row;
}

// Identity rotations and centres whose mean is the origin, so the average pose is the
// identity and recentring changes nothing: the expected poses are the scaled inputs.
void RigPose(int i, double gl[3][4]) {
  const double centre[3] = {-0.45 + 0.1 * i, i % 2 ? 0.1 : -0.1, 0.0};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) gl[r][c] = r == c ? 1.0 : 0.0;
    gl[r][3] = centre[r];
  }
}

double Near(int i) { return 2.0 + 0.1 * i; }
double Far(int i) { return 20.0 + i; }

class LlffTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("ecrf_llff_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "images");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Dir() const { return dir_.string(); }

  void WriteBytes(const std::string& name, const std::vector<uint8_t>& bytes) const {
    std::ofstream(dir_ / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  // Images half the hwf size, named so that name order is not creation order.
  void WriteImages(const std::string& folder, int width, int height, float green) const {
    fs::create_directories(dir_ / folder);
    for (int i = kImages - 1; i >= 0; --i) {
      char name[32];
      std::snprintf(name, sizeof name, "img_%02d.png", i);
      Image image = MakeImage(width, height, 3, 0.0f);
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          image.at(x, y, 0) = i / 16.0f;  // tells the images apart
          image.at(x, y, 1) = green;      // tells the folders apart
        }
      }
      SavePng((dir_ / folder / name).string(), image);
    }
  }

  std::vector<double> RigTable() const {
    std::vector<double> table;
    for (int i = 0; i < kImages; ++i) {
      double gl[3][4];
      RigPose(i, gl);
      const std::vector<double> row = LlffRow(gl, Near(i), Far(i));
      table.insert(table.end(), row.begin(), row.end());
    }
    return table;
  }

  void WriteRig() const {
    WriteImages("images", 32, 24, 0.25f);
    WriteBytes("poses_bounds.npy", NpyBytes(RigTable(), "(10, 17)"));
  }

  fs::path dir_;
};

TEST_F(LlffTest, ParsesPosesIntrinsicsBoundsAndSplit) {
  WriteRig();
  const DatasetManifest train = ReadDatasetManifest(Dir(), "train");
  const DatasetManifest test = ReadDatasetManifest(Dir(), "test");
  ASSERT_EQ(train.views.size(), 8u);
  ASSERT_EQ(test.views.size(), 2u);    // NeRF's llffhold 8: images 0 and 8
  EXPECT_TRUE(train.estimated_poses);  // LLFF poses come from COLMAP
  EXPECT_EQ(test.views[0].name, "img_00");
  EXPECT_EQ(test.views[1].name, "img_08");
  EXPECT_EQ(train.views[0].name, "img_01");
  EXPECT_EQ(train.views[7].name, "img_09");
  EXPECT_EQ(ReadDatasetManifest(Dir(), "val").views.size(), 2u);

  const double scale = 1.0 / (Near(0) * 0.75);
  for (const DatasetManifest* split : {&train, &test}) {
    for (const ViewSource& view : split->views) {
      const int i = std::stoi(view.name.substr(4));
      double gl[3][4];
      RigPose(i, gl);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(view.camera.c2w[r][c], gl[r][c], 1e-12) << view.name;
        EXPECT_NEAR(view.camera.c2w[r][3], gl[r][3] * scale, 1e-12) << view.name;
      }
      EXPECT_EQ(view.camera.width, 32);
      EXPECT_EQ(view.camera.height, 24);
      EXPECT_DOUBLE_EQ(view.camera.fx, kFocal / 2);  // hwf is for 64x48
      EXPECT_DOUBLE_EQ(view.camera.fy, kFocal / 2);
      EXPECT_EQ(view.camera.cx, 16.0);
      EXPECT_EQ(view.camera.cy, 12.0);
      EXPECT_FALSE(view.camera.HasDistortion());
      EXPECT_TRUE(Contains(view.image_path, "images"));
    }
  }
  EXPECT_FALSE(train.white_background);
  EXPECT_NEAR(train.near, 0.9 * Near(0) * scale, 1e-12);  // 1.2: the nearest bound becomes 4/3
  EXPECT_NEAR(train.far, Far(kImages - 1) * scale, 1e-12);
  for (int a = 0; a < 3; ++a) {
    EXPECT_TRUE(std::isfinite(train.scene_aabb[0][a]) && std::isfinite(train.scene_aabb[1][a]));
    EXPECT_EQ(train.scene_aabb[0][a],
              test.scene_aabb[0][a]);  // from every camera, whatever the split
  }
  // Cameras look down -z, so the box reaches the far bound in front of them and stops behind.
  EXPECT_NEAR(train.scene_aabb[0][2], -Far(kImages - 1) * scale, 1e-9);
  EXPECT_NEAR(train.scene_aabb[1][2], 0.0, 1e-12);
}

// Recentring removes any rigid motion of the whole rig: a rotated, shifted capture loads the same.
TEST_F(LlffTest, RecentringUndoesAGlobalRigidMotion) {
  WriteRig();
  const DatasetManifest plain = ReadDatasetManifest(Dir(), "train");
  const double angle = 0.7, c = std::cos(angle), s = std::sin(angle);
  const double motion[3][4] = {{c, 0, s, 3.0}, {0, 1, 0, -2.0}, {-s, 0, c, 5.0}};
  std::vector<double> table;
  for (int i = 0; i < kImages; ++i) {
    double gl[3][4], moved[3][4];
    RigPose(i, gl);
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 4; ++k) {
        moved[r][k] = k == 3 ? motion[r][3] : 0.0;
        for (int j = 0; j < 3; ++j) moved[r][k] += motion[r][j] * gl[j][k];
      }
    }
    const std::vector<double> row = LlffRow(moved, Near(i), Far(i));
    table.insert(table.end(), row.begin(), row.end());
  }
  WriteBytes("poses_bounds.npy", NpyBytes(table, "(10, 17)", "<f8", 2));  // also a version 2 header
  const DatasetManifest moved = ReadDatasetManifest(Dir(), "train");
  ASSERT_EQ(moved.views.size(), plain.views.size());
  for (size_t v = 0; v < plain.views.size(); ++v) {
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 4; ++k)
        EXPECT_NEAR(moved.views[v].camera.c2w[r][k], plain.views[v].camera.c2w[r][k], 1e-9);
    }
  }
}

TEST_F(LlffTest, DownscaleUsesImagesNOrShrinksOnLoad) {
  WriteRig();
  const Dataset shrunk = LoadDataset(Dir(), "test", 2);  // no images_2: area-downscaled on load
  ASSERT_EQ(shrunk.views.size(), 2u);
  EXPECT_EQ(shrunk.views[0].rgb.width, 16);
  EXPECT_EQ(shrunk.views[0].camera.width, 16);
  EXPECT_DOUBLE_EQ(shrunk.views[0].camera.fx, kFocal / 4);
  EXPECT_NEAR(shrunk.views[0].rgb.at(3, 3, 1), 0.25f, 1e-2);

  WriteImages("images_2", 16, 12, 0.75f);
  const Dataset prescaled = LoadDataset(Dir(), "test", 2);
  EXPECT_EQ(prescaled.views[0].rgb.width, 16);
  EXPECT_EQ(prescaled.views[0].camera.width, 16);
  EXPECT_DOUBLE_EQ(prescaled.views[0].camera.fx, kFocal / 4);
  EXPECT_NEAR(prescaled.views[0].rgb.at(3, 3, 1), 0.75f, 1e-2) << "images_2 was not used";
  EXPECT_NEAR(prescaled.views[1].rgb.at(3, 3, 0), 8 / 16.0f, 1e-2) << "test view 1 is img_08";

  // --downscale 4 with images_2 but no images_4: images_2 shrunk by 2 on load, not the originals.
  const Dataset quarter = LoadDataset(Dir(), "test", 4);
  EXPECT_EQ(quarter.views[0].rgb.width, 8);
  EXPECT_EQ(quarter.views[0].camera.width, 8);
  EXPECT_DOUBLE_EQ(quarter.views[0].camera.fx, kFocal / 8);
  EXPECT_NEAR(quarter.views[0].rgb.at(1, 1, 1), 0.75f, 1e-2) << "images_2 was not used";
  // A factor that images_2 does not divide falls back to the originals.
  const Dataset third = LoadDataset(Dir(), "test", 3);
  EXPECT_NEAR(third.views[0].rgb.at(1, 1, 1), 0.25f, 1e-2) << "images_2 used for --downscale 3";
}

TEST_F(LlffTest, ErrorsNameTheFileAndTheProblem) {
  WriteImages("images", 32, 24, 0.25f);
  const std::string npy = (dir_ / "poses_bounds.npy").string();
  auto error = [&] { return ErrorOf([&] { ReadDatasetManifest(Dir(), "train"); }); };

  WriteBytes("poses_bounds.npy", {'n', 'o', 't', ' ', 'n', 'p', 'y', 0, 0, 0, 0, 0});
  EXPECT_TRUE(Contains(error(), npy) && Contains(error(), "not a .npy file")) << error();

  std::vector<double> table = RigTable();
  WriteBytes("poses_bounds.npy",
             NpyBytes(std::vector<double>(table.begin(), table.end() - 17), "(9, 17)"));
  EXPECT_TRUE(Contains(error(), npy) && Contains(error(), "9 poses") &&
              Contains(error(), "10 images"))
      << error();

  WriteBytes("poses_bounds.npy",
             NpyBytes(std::vector<double>(table.begin(), table.begin() + 150), "(10, 15)"));
  EXPECT_TRUE(Contains(error(), "10 x 15") && Contains(error(), "N x 17")) << error();

  WriteBytes("poses_bounds.npy",
             NpyBytes(std::vector<double>(table.begin(), table.end() - 5), "(10, 17)"));
  EXPECT_TRUE(Contains(error(), npy) && Contains(error(), "truncated")) << error();

  WriteBytes("poses_bounds.npy", NpyBytes(table, "(10, 17)", "<i8"));
  EXPECT_TRUE(Contains(error(), "dtype '<i8'")) << error();

  WriteBytes("poses_bounds.npy", NpyBytes(table, "(170,)"));
  EXPECT_TRUE(Contains(error(), "2-D")) << error();

  std::vector<double> bad = table;
  bad[3 * 17 + 7] = std::numeric_limits<double>::quiet_NaN();
  WriteBytes("poses_bounds.npy", NpyBytes(bad, "(10, 17)"));
  EXPECT_TRUE(Contains(error(), npy) && Contains(error(), "row 3, column 7 is not finite"))
      << error();

  bad = table;
  bad[2 * 17 + 15] = -1.0;  // near bound
  WriteBytes("poses_bounds.npy", NpyBytes(bad, "(10, 17)"));
  EXPECT_TRUE(Contains(error(), "row 2") && Contains(error(), "near")) << error();

  bad = table;
  bad[4] = 60;  // h: the 32x24 images are no longer 64x60 in shape
  WriteBytes("poses_bounds.npy", NpyBytes(bad, "(10, 17)"));
  EXPECT_TRUE(Contains(error(), "img_00.png") && Contains(error(), "64x60")) << error();

  // An image name that cannot be followed (a symlink loop) is named with its cause, not left out
  // (the poses pair with the images by position).
  WriteBytes("poses_bounds.npy", NpyBytes(table, "(10, 17)"));
  const fs::path loop = dir_ / "images/img_05.png";
  fs::remove(loop);
  fs::create_symlink(loop.filename(), loop);
  EXPECT_TRUE(Contains(error(), loop.string()) && Contains(error(), "symbolic links")) << error();

  fs::remove_all(dir_ / "images");
  EXPECT_TRUE(Contains(error(), "images") && Contains(error(), "no such directory")) << error();
}

// The poses and intrinsics pass the checks of the JSON loaders (trainer/data/camera.h) before any
// training: a zero, scaled or mirrored rotation, a focal length that leaves no field of view, and
// bounds that put the cameras at infinity are refused, naming the file and the row.
TEST_F(LlffTest, PosesAndIntrinsicsAreValidatedAsInTheJsonLoaders) {
  WriteImages("images", 32, 24, 0.25f);
  const std::string npy = (dir_ / "poses_bounds.npy").string();
  auto error_for = [&](const std::vector<double>& rows) {
    WriteBytes("poses_bounds.npy", NpyBytes(rows, "(10, 17)"));
    return ErrorOf([&] { ReadDatasetManifest(Dir(), "train"); });
  };
  const std::vector<double> table = RigTable();
  auto rotation = [](std::vector<double>& rows, int row, double scale) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rows[size_t(row) * 17 + r * 5 + c] *= scale;
  };
  std::vector<double> bad = table;
  rotation(bad, 3, 0.0);
  std::string error = error_for(bad);
  EXPECT_TRUE(Contains(error, npy) && Contains(error, "row 3: the rotation is not orthonormal"))
      << error;
  bad = table;
  rotation(bad, 4, 5.0);
  EXPECT_TRUE(Contains(error_for(bad), "row 4: the rotation is not orthonormal")) << error_for(bad);
  bad = table;
  for (int r = 0; r < 3; ++r) bad[size_t(5) * 17 + r * 5 + 2] *= -1.0;  // mirror the back axis
  EXPECT_TRUE(Contains(error_for(bad), "row 5: the rotation is a reflection")) << error_for(bad);
  bad = table;
  bad[size_t(6) * 17 + 14] = 1e-300;  // focal length
  EXPECT_TRUE(Contains(error_for(bad), "row 6: the focal length")) << error_for(bad);
  bad = table;
  for (int row = 0; row < 10; ++row) {
    bad[size_t(row) * 17 + 15] = 1e-300;
    bad[size_t(row) * 17 + 16] = 2e-300;
  }
  error = error_for(bad);
  EXPECT_TRUE(Contains(error, npy) && Contains(error, "the bounds do not fit the poses")) << error;
  EXPECT_NO_THROW(error_for(table));
  EXPECT_EQ(error_for(table), "");
}

TEST_F(LlffTest, LayoutIsDetectedAndAnEmptyDirectorySaysWhatItLookedFor) {
  const std::string message = ErrorOf([&] { ReadDatasetManifest(Dir(), "train"); });
  EXPECT_TRUE(Contains(message, "transforms_train.json") && Contains(message, "transforms.json") &&
              Contains(message, "poses_bounds.npy"))
      << message;
  WriteRig();
  EXPECT_EQ(LoadDataset(Dir(), "train", 1).views.size(), 8u);
}

TEST(LlffNpy, ReadsFloat32AndVersion3Headers) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }";
  while ((12 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::vector<uint8_t> bytes = {0x93, 'N', 'U', 'M', 'P', 'Y', 3, 0, uint8_t(header.size()),
                                0,    0,   0};
  bytes.insert(bytes.end(), header.begin(), header.end());
  for (float v : {1.5f, -2.0f, 0.25f, 8.0f}) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int b = 0; b < 4; ++b) bytes.push_back(uint8_t(bits >> (8 * b)));
  }
  const NpyMatrix m = ParseNpyMatrix("x.npy", bytes);
  EXPECT_EQ(m.rows, 2);
  EXPECT_EQ(m.cols, 2);
  EXPECT_EQ(m.values, (std::vector<double>{1.5, -2.0, 0.25, 8.0}));
  bytes[6] = 4;
  EXPECT_TRUE(Contains(ErrorOf([&] { ParseNpyMatrix("x.npy", bytes); }), "version 4"));
}

}  // namespace
}  // namespace ecrf::trainer
