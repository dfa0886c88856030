// The frames the model's input state reads, defined once for the viewer's trace and rollout logic.
#pragma once

namespace dynscope {

/// Frames the model's state at t reads: p(t), p(t−1) and p(t−2) give v(t) and v(t−1) (DESIGN §5).
inline constexpr int kStateHistoryFrames = 3;

/// First frame whose state can be built, so the first one a forward pass can be traced at.
inline constexpr int kFirstTraceableFrame = kStateHistoryFrames - 1;

/// First frame t of a rollout with `observed_frames` ground-truth frames whose pass produced a
/// predicted frame (t+1 ≥ observed_frames), so the first a rollout-state trace can record.
inline constexpr int first_rollout_trace_frame(int observed_frames) {
  return observed_frames - 1 > kFirstTraceableFrame ? observed_frames - 1 : kFirstTraceableFrame;
}

}  // namespace dynscope
