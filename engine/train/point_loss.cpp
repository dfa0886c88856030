// The training loss over a batch's points.
#include "engine/train/point_loss.h"

namespace dynscope {

torch::Tensor point_loss_sum(const torch::Tensor& predicted, const torch::Tensor& truth,
                             const Vec3& target_std, double delta, const torch::Tensor& moving) {
  const torch::Tensor std =
      torch::tensor({target_std.x(), target_std.y(), target_std.z()}, torch::kDouble);
  torch::Tensor err = ((predicted - truth) / std).to(torch::kFloat);
  if (moving.defined()) err = err * moving;
  return torch::nn::functional::huber_loss(
      err, torch::zeros_like(err),
      torch::nn::functional::HuberLossFuncOptions().reduction(torch::kSum).delta(delta));
}

}  // namespace dynscope
