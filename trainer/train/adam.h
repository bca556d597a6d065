// Adam over a flat float array, the update PyTorch's torch.optim.Adam performs (no weight decay,
// no amsgrad), with bias correction and a learning rate the caller changes between steps.
#ifndef ECRF_TRAINER_TRAIN_ADAM_H_
#define ECRF_TRAINER_TRAIN_ADAM_H_

#include <cstddef>
#include <vector>

namespace ecrf {
namespace trainer {

struct AdamConfig {
  float beta1 = 0.9f;
  float beta2 = 0.99f;  // TensoRF uses betas (0.9, 0.99)
  float epsilon = 1e-8f;
};

class Adam {
 public:
  Adam() = default;
  Adam(size_t size, const AdamConfig& config);
  // Forget the moments and the step count (TensoRF rebuilds its optimizer at each upsample).
  void Reset(size_t size);
  // params -= lr * mhat / (sqrt(vhat) + eps); parallel over the array (OpenMP).
  void Step(float* params, const float* grads, size_t size, float learning_rate);
  // Keeps only the moments at these indices, in this order (the parameters were pruned the same
  // way: VmGrid::KeptIndices, AppearanceHead::KeptIndices); the step count stays.
  void Keep(const std::vector<size_t>& indices);
  size_t size() const { return m_.size(); }
  long step_count() const { return step_; }
  // For checkpoints.
  std::vector<float>& first_moment() { return m_; }
  std::vector<float>& second_moment() { return v_; }
  const std::vector<float>& first_moment() const { return m_; }
  const std::vector<float>& second_moment() const { return v_; }
  void set_step_count(long step) { step_ = step; }

 private:
  AdamConfig config_;
  std::vector<float> m_, v_;
  long step_ = 0;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_ADAM_H_
