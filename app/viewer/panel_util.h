// Small helpers shared by the panel files (colours, number formatting, section headers).
#pragma once

#include <imgui.h>

#include <string>

#include "engine/core/types.h"
#include "render/colormap.h"

namespace dynscope::app::viewer {

/// Grey used for hints and secondary text.
inline const ImVec4 kMutedText(0.65f, 0.65f, 0.65f, 1.0f);

inline ImVec4 to_imvec(const render::Color& c) { return ImVec4(c.x(), c.y(), c.z(), 1.0f); }

/// "(x, y, z)" with `format` per component.
std::string format_vec(const Vec3& v, const char* format = "%.3f");

/// The last component of a slash-separated path.
std::string file_name(const std::string& path);

/// A horizontal colour bar of `colormap` over [lo, hi] with its end values.
void draw_colorbar(const std::string& colormap, float lo, float hi);

}  // namespace dynscope::app::viewer
