// ecrf_conformance_checksums DIR: decodes every conformance vector in DIR with nothing but format/
// and decoder/, checks the coefficient outputs against coefficients.md5 and the grids against
// scenes.md5, and prints every checksum of SPEC.md 6.5 plus the MD5 of each reference-camera
// render. scripts/conformance-matrix.sh builds it with several compilers, optimisation levels and
// for WebAssembly, and requires identical checksum lines from all of them: the decoded output must
// not depend on the platform. Render lines are printed for information (7.7 allows differences).
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "conformance/coef_vectors.h"
#include "conformance/conformance_camera.h"
#include "conformance/grid_md5.h"
#include "conformance/reject_check.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"

namespace {

using ecrf::Status;

bool ReadFile(const std::string& path, std::vector<uint8_t>* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return true;
}

std::vector<std::pair<std::string, std::string>> ReadMd5List(const std::string& path) {
  std::vector<std::pair<std::string, std::string>> list;
  std::ifstream in(path);
  std::string file, md5;
  while (in >> file >> md5) list.emplace_back(file, md5);
  return list;
}

std::string RenderMd5(const ecrf::dec::SceneField& field, const std::string& name,
                      std::string* error) {
  const ecrf::dec::Camera cam = ecrf::conformance::ReferenceCamera(name);
  ecrf::dec::RenderOptions options;
  options.early_stop_transmittance = 0.f;  // the exact reference process
  options.num_threads = 1;
  ecrf::dec::RayMarcher marcher;
  std::vector<uint8_t> rgba(size_t(cam.width) * cam.height * 4);
  Status s = marcher.Init(&field, options);
  if (s.ok()) s = marcher.RenderImage(cam, rgba.data(), nullptr);
  if (!s.ok()) {
    *error = s.message();
    return "";
  }
  ecrf::conformance::Md5 md5;
  for (size_t p = 0; p < rgba.size(); p += 4) md5.Update(&rgba[p], 3);  // RGB, as the PNG holds
  return md5.HexDigest();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s tests/conformance\n", argv[0]);
    return 2;
  }
  const std::string dir = std::string(argv[1]) + "/";
  int failures = 0;
  const auto coef_list = ReadMd5List(dir + "coefficients.md5");
  for (const auto& v : ecrf::conformance::CoefVectors()) {
    const std::string file = std::string(v.name) + ".bin";
    std::vector<uint8_t> bytes;
    if (!ReadFile(dir + file, &bytes)) {
      std::fprintf(stderr, "%s: cannot read\n", (dir + file).c_str());
      return 2;
    }
    const std::string md5 = ecrf::conformance::DecodeVectorMd5(v, bytes);
    std::string expected;
    for (const auto& [f, m] : coef_list)
      if (f == file) expected = m;
    const bool ok = md5 == expected;
    failures += !ok;
    std::printf("coefficients %s %s%s\n", file.c_str(), md5.c_str(), ok ? "" : " MISMATCH");
  }
  const auto scene_list = ReadMd5List(dir + "scenes.md5");
  if (scene_list.empty()) {
    std::fprintf(stderr, "%sscenes.md5: missing or empty\n", dir.c_str());
    return 2;
  }
  for (const auto& [file, expected] : scene_list) {
    std::vector<uint8_t> bytes;
    if (!ReadFile(dir + file, &bytes)) {
      std::fprintf(stderr, "%s: cannot read\n", (dir + file).c_str());
      return 2;
    }
    ecrf::dec::SceneField field;
    const Status s = ecrf::dec::DecodeScene(bytes.data(), bytes.size(), ecrf::dec::DecodeOptions(),
                                            &field, nullptr);
    if (!s.ok()) {
      std::printf("scene %s DECODE ERROR %s\n", file.c_str(), s.message());
      ++failures;
      continue;
    }
    const std::string grids = ecrf::conformance::SceneGridMd5(field);
    const bool ok = grids == expected;
    failures += !ok;
    std::printf("scene %s grids %s occupancy %s mlp %s%s\n", file.c_str(), grids.c_str(),
                ecrf::conformance::OccupancyMd5(field).c_str(),
                ecrf::conformance::MlpMd5(field).c_str(), ok ? "" : " MISMATCH");
    std::string error;
    const std::string name = file.substr(0, file.size() - 5);  // without ".ecrf"
    const std::string render = RenderMd5(field, name, &error);
    std::printf("render %s %s\n", file.c_str(),
                render.empty() ? ("ERROR " + error).c_str() : render.c_str());
    failures += render.empty();
  }
  // Must-reject streams (SPEC.md 7.7): "FILE STAGE CODE KIND" per line of reject/expected.txt. A
  // decode-stage stream fails to decode with CODE; a render-stage one decodes and its renderer
  // refuses it with CODE when prepared. Printed with the code so that every build agrees.
  std::ifstream expected(dir + "reject/expected.txt");
  if (!expected) {
    std::fprintf(stderr, "%sreject/expected.txt: missing\n", dir.c_str());
    return 2;
  }
  std::string file, stage, kind;
  int code = 0;
  while (expected >> file >> stage >> code >> kind) {
    std::vector<uint8_t> bytes;
    if (!ReadFile(dir + "reject/" + file, &bytes)) {
      std::fprintf(stderr, "%sreject/%s: cannot read\n", dir.c_str(), file.c_str());
      return 2;
    }
    const ecrf::conformance::RejectOutcome out =
        ecrf::conformance::CheckReject(bytes.data(), bytes.size(), stage);
    const bool ok = out.RefusedWith(code);
    failures += !ok;
    std::printf("reject %s %s %d %s%s\n", file.c_str(), stage.c_str(), out.status.code(),
                kind.c_str(), ok ? "" : " NOT AS EXPECTED");
  }
  std::printf("%s\n",
              failures ? "conformance checksums: FAILED" : "conformance checksums: all match");
  return failures ? 1 : 0;
}
