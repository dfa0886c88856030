// Colormaps: viridis and turbo for scalars, a categorical palette for object ids.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace dynscope::render {

/// Linear RGB colour with channels in [0, 1].
using Color = Eigen::Vector3f;

/// Names accepted by colormap(): "viridis", "turbo".
const std::vector<std::string>& colormap_names();
/// Throws ValueError("colormap", ...) listing the valid names if `name` is not one of them.
void check_colormap(const std::string& name);
/// Colour of `t` (clamped to [0, 1]) under the named colormap; throws ValueError for a bad name.
Color colormap(const std::string& name, float t);
/// The colormap sampled at 256 evenly spaced t as RGBA8 (the GPU lookup texture), `[256*4]`.
std::vector<uint8_t> colormap_table(const std::string& name);
/// Colour of category `id` (an object id): the 10-colour Tableau palette, cycled, then darkened
/// every cycle so ids 0..29 stay distinct. Negative ids are grey.
Color categorical_color(int64_t id);
/// categorical_color of every id, packed RGB `[3 * ids.size()]` (a PointSeries' colours).
std::vector<float> categorical_colors(const std::vector<int32_t>& ids);

}  // namespace dynscope::render
