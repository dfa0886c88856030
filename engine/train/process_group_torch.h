// Tensor collectives of a ProcessGroup (LibTorch inside engine/train only).
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "engine/train/process_group.h"

namespace dynscope {

/// Default bucket size of the flattened collectives (bytes).
constexpr int64_t kCollectiveBucketBytes = int64_t{16} << 20;

/// Overwrites every tensor with rank 0's values: the tensors are flattened into buckets of at
/// most `bucket_bytes` per dtype, one broadcast per bucket.
void broadcast_tensors(ProcessGroup& group, const std::vector<torch::Tensor>& tensors,
                       const char* what, int64_t bucket_bytes = kCollectiveBucketBytes);

/// Replaces every tensor by its sum over the ranks, bucketed like broadcast_tensors (one
/// all-reduce per bucket, never one per tensor). Every rank ends with identical values.
void allreduce_sum(ProcessGroup& group, const std::vector<torch::Tensor>& tensors, const char* what,
                   int64_t bucket_bytes = kCollectiveBucketBytes);

}  // namespace dynscope
