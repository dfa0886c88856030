// The frames the model's input state reads, defined once for the viewer's trace and rollout logic.
#pragma once

namespace dynscope {

/// Frames the model's state at t reads: p(t), p(t−1) and p(t−2) give v(t) and v(t−1) (DESIGN §5).
inline constexpr int kStateHistoryFrames = 3;

/// First frame whose state can be built, so the first one a forward pass can be traced at.
inline constexpr int kFirstTraceableFrame = kStateHistoryFrames - 1;

}  // namespace dynscope
