// Training checkpoints: named float arrays with shapes plus a JSON document, zstd-compressed.
// Written to a temporary file and renamed, so a crash never leaves a half-written checkpoint.
#ifndef ECRF_TRAINER_TRAIN_CHECKPOINT_H_
#define ECRF_TRAINER_TRAIN_CHECKPOINT_H_

#include <cstdint>
#include <string>
#include <vector>

namespace ecrf {
namespace trainer {

struct CheckpointArray {
  std::string name;
  std::vector<int64_t> shape;
  std::vector<float> data;  // row-major, product(shape) elements
};

struct Checkpoint {
  std::string json;  // training state that is not an array (iteration, options, aabb, ...)
  std::vector<CheckpointArray> arrays;

  const CheckpointArray* Find(const std::string& name) const;
};

// Throws std::runtime_error naming the path and the problem.
void WriteCheckpoint(const std::string& path, const Checkpoint& checkpoint, int zstd_level = 3);
Checkpoint ReadCheckpoint(const std::string& path);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_CHECKPOINT_H_
