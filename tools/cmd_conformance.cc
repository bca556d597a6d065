// `ecrf conformance --write DIR | --check DIR`: rebuilds the conformance vectors of
// tests/conformance, or checks that the checked-in ones still decode to their MD5s and are what
// this encoder writes (if not, the format changed).
//
// Two families: raw coefficient streams (coefficients.md5, SPEC.md sections 3-5) and whole .ecrf
// scenes (scenes.md5, section 6) with a reference render each; manifest.json holds every vector's
// parameters, checksums and exact camera, and --check renders each scene with that camera and
// applies the tolerance of SPEC.md 7.7 to the reference render. The hand-made scenes are rebuilt
// bit for bit from integers; scene_builtin.ecrf comes from training, which is not bit-reproducible
// across compilers, so --check only decodes it and --write keeps it (--retrain-builtin retrains).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>

#include "conformance/coef_vectors.h"
#include "conformance/conformance_camera.h"
#include "conformance/reject_check.h"
#include "conformance/reject_vectors.h"
#include "conformance/scene_vectors.h"
#include "decoder/ray_marcher.h"
#include "encoder/scene_encoder.h"
#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/conformance_manifest.h"
#include "tools/decoded_scene.h"
#include "trainer/data/file_io.h"
#include "trainer/data/image_io.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

using nlohmann::json;

// The reference render of SPEC.md 7.7: the exact process (no early termination), 8-bit RGBA.
std::vector<uint8_t> RenderReference(const dec::SceneField& scene, const dec::Camera& cam) {
  dec::RenderOptions options;
  options.early_stop_transmittance = 0.f;
  dec::RayMarcher marcher;
  std::vector<uint8_t> rgba(size_t(cam.width) * cam.height * 4);
  Status s = marcher.Init(&scene, options);
  if (s.ok()) s = marcher.RenderImage(cam, rgba.data(), nullptr);
  if (!s.ok()) throw std::runtime_error(std::string("reference render: ") + s.message());
  return rgba;
}

void SaveRgbPng(const std::string& path, const std::vector<uint8_t>& rgba, int width, int height) {
  trainer::Image img = trainer::MakeImage(width, height, 3);
  for (size_t p = 0; p < size_t(width) * height; ++p) {
    for (int c = 0; c < 3; ++c) img.pixels[p * 3 + c] = float(rgba[p * 4 + c]) / 255.f;
  }
  trainer::SavePng(path, img);
}

std::vector<uint8_t> LoadRgb8(const std::string& path) {
  const trainer::Image img = trainer::LoadImage(path);
  if (img.channels != 3) throw std::runtime_error(path + ": expected an RGB reference render");
  std::vector<uint8_t> rgb(img.pixels.size());
  for (size_t i = 0; i < rgb.size(); ++i)
    rgb[i] = uint8_t(std::lround(std::clamp(img.pixels[i], 0.f, 1.f) * 255.f));
  return rgb;
}

// The built-in scene, briefly trained and encoded: a realistic stream for decoders to check.
std::vector<uint8_t> TrainBuiltinStream() {
  trainer::TrainOptions o = trainer::PresetOptions("tiny");
  o.procedural_scene = trainer::ProceduralScene::kBuiltin;
  o.builtin_size = 48;
  o.builtin_views = 40;
  o.iters = 300;
  o.batch_rays = 1024;
  o.progress_every = 100;
  const trainer::Dataset train = trainer::LoadTrainingViews(o, "train");
  const trainer::Dataset test = trainer::LoadTrainingViews(o, "test");
  trainer::TensorfModel model(trainer::ConfigFor(o, train));
  trainer::RateState rate;
  trainer::Train(o, train, test, &model, &rate);
  encoder::EncodeOptions eo;
  eo.blocks = rate.config;
  eo.steps = rate.steps;
  eo.metadata_json = "{\"vector\":\"scene_builtin\",\"iterations\":300}";
  return trainer::EncodeScene(model, eo);
}

bool CamerasEqual(const dec::Camera& a, const dec::Camera& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy &&
         std::equal(std::begin(a.c2w), std::end(a.c2w), std::begin(b.c2w));
}

const json* FindEntry(const json& list, const std::string& file) {
  if (!list.is_array()) return nullptr;
  for (const json& e : list) {
    if (e.is_object() && e.value("file", "") == file) return &e;
  }
  return nullptr;
}

// --check of one scene vector against the manifest: checksums, encoder output, reference render.
int CheckScene(const std::string& dir, const std::string& name, const std::vector<uint8_t>& rebuilt,
               const json* entry, const std::map<std::string, std::string>& md5_list) {
  const std::string file = name + ".ecrf";
  const bool builtin = name == conformance::kBuiltinSceneVector;
  const std::vector<uint8_t> stored = trainer::ReadWholeFile(dir + "/" + file);
  const LoadedScene s = DecodeSceneBytes(stored, dir + "/" + file);
  const SceneChecksums sums = ComputeSceneChecksums(*s.field);
  if (entry == nullptr) {
    std::printf("%-36s MISSING from manifest.json\n", file.c_str());
    return 1;
  }
  const json& md5 = entry->at("md5");
  const auto listed = md5_list.find(file);
  const bool grids_ok = sums.grids == md5.value("grids", "") && listed != md5_list.end() &&
                        listed->second == sums.grids;
  const bool occ_ok = sums.occupancy == md5.value("occupancy", "");
  const bool mlp_ok = sums.mlp == md5.value("mlp", "");
  const bool bytes_ok = builtin || stored == rebuilt;
  const dec::Camera cam = CameraFromJson(entry->at("render").at("camera"), file + " camera");
  const RenderAgreement agree = CompareRenders(
      RenderReference(*s.field, cam), LoadRgb8(dir + "/" + entry->at("render").value("png", "")));
  std::printf("%-36s grids %s, occupancy %s, mlp %s, encoder output %s\n", file.c_str(),
              grids_ok ? "match" : "DIFFER", occ_ok ? "matches" : "DIFFERS",
              mlp_ok ? "matches" : "DIFFERS",
              builtin    ? "not rebuilt (trained)"
              : bytes_ok ? "identical"
                         : "CHANGED (format changed?)");
  char psnr[32] = "identical";
  if (agree.max_difference > 0) std::snprintf(psnr, sizeof(psnr), "%.1f dB", agree.psnr_db);
  std::printf(
      "%-36s render: %zu/%zu pixels within 2 codes (largest difference %d), %s%s%s\n", "",
      agree.within_two_codes, agree.pixels, agree.max_difference, psnr,
      agree.Conforms() ? "" : " -- FAILS SPEC.md 7.7",
      CamerasEqual(cam, conformance::ReferenceCamera(name))
          ? ""
          : " (this platform's OrbitCamera differs from the manifest's camera in the last bits)");
  return !grids_ok || !occ_ok || !mlp_ok || !bytes_ok || !agree.Conforms();
}

int CheckOrWriteScenes(const std::string& dir, bool write, bool retrain, json* manifest_scenes,
                       const json& stored_scenes) {
  int failures = 0;
  std::map<std::string, std::string> md5_list;
  if (!write) {
    std::ifstream in(dir + "/scenes.md5");
    std::string file, md5;
    while (in >> file >> md5) md5_list[file] = md5;
  }
  std::vector<std::pair<std::string, std::vector<uint8_t>>> streams;
  for (const auto& v : conformance::SceneVectors())
    streams.emplace_back(v.name, conformance::BuildSceneVector(v));
  // Training is slow and not bit-reproducible: keep the checked-in stream unless asked.
  const std::string builtin_path = dir + "/" + conformance::kBuiltinSceneVector + ".ecrf";
  std::vector<uint8_t> builtin_bytes;
  if (write) {
    std::ifstream probe(builtin_path);
    builtin_bytes = retrain || !probe ? TrainBuiltinStream() : trainer::ReadWholeFile(builtin_path);
  }
  streams.emplace_back(conformance::kBuiltinSceneVector, builtin_bytes);
  std::ostringstream md5_text;
  for (auto& [name, bytes] : streams) {
    const std::string file = name + ".ecrf";
    if (!write) {
      failures += CheckScene(dir, name, bytes, FindEntry(stored_scenes, file), md5_list);
      continue;
    }
    const LoadedScene s = DecodeSceneBytes(bytes, dir + "/" + file);
    const SceneChecksums sums = ComputeSceneChecksums(*s.field);
    const dec::Camera cam = conformance::ReferenceCamera(name);
    trainer::WriteFileAtomically(dir + "/" + file, bytes.data(), bytes.size());
    SaveRgbPng(dir + "/" + name + ".png", RenderReference(*s.field, cam), cam.width, cam.height);
    manifest_scenes->push_back(
        SceneVectorJson(file, bytes.size(), *s.field, s.info, sums, cam, name + ".png"));
    md5_text << file << " " << sums.grids << "\n";
    std::printf("wrote %s/%s (%zu bytes, grids md5 %s) and its reference render\n", dir.c_str(),
                file.c_str(), bytes.size(), sums.grids.c_str());
  }
  if (write) {
    const std::string text = md5_text.str();
    trainer::WriteFileAtomically(dir + "/scenes.md5", text.data(), text.size());
  }
  return failures;
}

}  // namespace

// The must-reject streams of conformance/reject_vectors.h in DIR/reject/: written, or checked
// byte for byte against this encoder's and refused with their category by this decoder.
int CheckOrWriteRejects(const std::string& dir, bool write, json* manifest_rejects) {
  const std::vector<conformance::RejectVector> vectors = conformance::RejectVectors();
  const std::string reject_dir = dir + "/reject";
  if (write) MakeDirectory(reject_dir);
  int failures = 0;
  for (const conformance::RejectVector& r : vectors) {
    const std::string file = r.name + ".ecrf";
    manifest_rejects->push_back({{"file", "reject/" + file},
                                 {"stage", r.stage},
                                 {"error", ErrorCodeName(r.code)},
                                 {"code", r.code},
                                 {"kind", r.budget ? "budget" : "normative"},
                                 {"why", r.why},
                                 {"bytes", r.bytes.size()}});
    if (write) {
      trainer::WriteFileAtomically(reject_dir + "/" + file, r.bytes.data(), r.bytes.size());
      continue;
    }
    const std::vector<uint8_t> stored = trainer::ReadWholeFile(reject_dir + "/" + file);
    const conformance::RejectOutcome out =
        conformance::CheckReject(stored.data(), stored.size(), r.stage);
    const bool refused = out.RefusedWith(r.code);
    const Status& s = out.status;
    const bool same_bytes = stored == r.bytes;
    std::printf("%-44s %s %s (%s), encoder output %s\n", ("reject/" + file).c_str(), r.stage,
                refused ? "refused as expected:" : "NOT REFUSED AS EXPECTED:",
                s.ok() ? "ok" : s.message(), same_bytes ? "identical" : "CHANGED");
    failures += !refused || !same_bytes;
  }
  if (write) {
    const std::string text = conformance::RejectExpectedText(vectors);
    trainer::WriteFileAtomically(reject_dir + "/expected.txt", text.data(), text.size());
    std::printf("wrote %zu must-reject streams and expected.txt into %s\n", vectors.size(),
                reject_dir.c_str());
  }
  return failures;
}

int RunConformance(int argc, char** argv) {
  std::string write_dir, check_dir;
  bool retrain = false;
  auto app = MakeCommand(
      "conformance",
      "rebuild (--write DIR) or check (--check DIR) the conformance vectors of tests/conformance: "
      "their MD5s, that this encoder still writes them byte for byte (if not, the format "
      "changed), and the reference renders within the tolerance of SPEC.md 7.7");
  CLI::Option* write_flag =
      app->add_option("--write", write_dir,
                      "write every vector, its checksums and manifest.json into DIR")
          ->type_name("DIR");
  CLI::Option* check_flag =
      app->add_option("--check", check_dir, "check the vectors in DIR against their manifest")
          ->type_name("DIR");
  write_flag->excludes(check_flag);
  app->add_flag("--retrain-builtin", retrain,
                "with --write: retrain scene_builtin.ecrf (training is not bit-reproducible across "
                "compilers, "
                "so --write keeps the existing one otherwise)")
      ->needs(write_flag);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (write_dir.empty() && check_dir.empty()) {
    std::fprintf(stderr, "%s: error: needs --write DIR or --check DIR; see '%s --help'\n",
                 app->get_name().c_str(), app->get_name().c_str());
    return 2;
  }
  const bool write = !write_dir.empty();
  const std::string dir = write ? write_dir : check_dir;
  json stored = json::object();
  if (!write) {
    const std::vector<uint8_t> text = trainer::ReadWholeFile(dir + "/manifest.json");
    stored = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
    if (stored.is_discarded() || !stored.is_object())
      throw std::runtime_error(dir + "/manifest.json: not a JSON object");
  }
  json manifest = {
      {"spec", "SPEC.md 1.10"},
      {"note",
       "written by `ecrf conformance --write`; checksums as in SPEC.md 6.5, cameras exact (7.1)"},
      {"coefficient_vectors", json::array()},
      {"scene_vectors", json::array()},
      {"reject_vectors", json::array()}};
  const json stored_coefs = stored.value("coefficient_vectors", json::array());
  const json stored_scenes = stored.value("scene_vectors", json::array());
  std::ostringstream coef_md5_text;
  int failures = 0;
  for (const auto& v : conformance::CoefVectors()) {
    const std::vector<uint8_t> stream = conformance::EncodeVector(v);
    const std::string md5 = conformance::DecodeVectorMd5(v, stream);
    const std::string file = std::string(v.name) + ".bin";
    const std::string path = dir + "/" + file;
    coef_md5_text << file << " " << md5 << "\n";
    manifest["coefficient_vectors"].push_back({{"file", file},
                                               {"block", {v.shape.n0, v.shape.n1, v.shape.n2}},
                                               {"blocks", v.blocks},
                                               {"coef_bits", v.coef_bits},
                                               // The value of a COEF payload's `contexts` byte
                                               // (SPEC.md 6.4.2): 0 narrow, 1 wide, 2 neighbour.
                                               {"contexts", static_cast<int>(v.contexts)},
                                               {"grid", {v.grid[0], v.grid[1], v.grid[2]}},
                                               {"bytes", stream.size()},
                                               {"md5", md5}});
    if (write) {
      trainer::WriteFileAtomically(path, stream.data(), stream.size());
      std::printf("wrote %s (%zu bytes, output md5 %s)\n", path.c_str(), stream.size(),
                  md5.c_str());
      continue;
    }
    const std::vector<uint8_t> bytes = trainer::ReadWholeFile(path);
    const std::string stored_md5 = conformance::DecodeVectorMd5(v, bytes);
    const json* entry = FindEntry(stored_coefs, file);
    const bool md5_ok = stored_md5 == md5 && entry != nullptr && entry->value("md5", "") == md5;
    const bool same_bytes = bytes == stream;
    std::printf("%-36s decode %s, encoder output %s\n", file.c_str(),
                md5_ok ? "matches" : "DIFFERS",
                same_bytes ? "identical" : "CHANGED (format changed?)");
    failures += !md5_ok || !same_bytes;
  }
  if (write) {
    const std::string text = coef_md5_text.str();
    trainer::WriteFileAtomically(dir + "/coefficients.md5", text.data(), text.size());
  }
  failures += CheckOrWriteScenes(dir, write, retrain, &manifest["scene_vectors"], stored_scenes);
  failures += CheckOrWriteRejects(dir, write, &manifest["reject_vectors"]);
  if (write) {
    const std::string text = ManifestText(manifest);
    trainer::WriteFileAtomically(dir + "/manifest.json", text.data(), text.size());
    std::printf("wrote %s/coefficients.md5, scenes.md5 and manifest.json\n", dir.c_str());
  }
  if (!write)
    std::printf("%s\n", failures ? "conformance: FAILED" : "conformance: all vectors match");
  return failures ? 1 : 0;
}

}  // namespace tools
}  // namespace ecrf
