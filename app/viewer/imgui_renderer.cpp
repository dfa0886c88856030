// ImGui draw data → render::UiDrawData (see imgui_renderer.h).
#include "app/viewer/imgui_renderer.h"

#include <imgui.h>

#include <cstddef>
#include <cstdint>

#include "render/gl_context.h"

namespace dynscope::app::viewer {

// UiVertex is ImDrawVert's layout, so ImGui's vertex buffers are handed over without a copy.
static_assert(sizeof(ImDrawVert) == sizeof(render::UiVertex), "ImDrawVert layout changed");
static_assert(offsetof(ImDrawVert, pos) == offsetof(render::UiVertex, x), "ImDrawVert layout");
static_assert(offsetof(ImDrawVert, uv) == offsetof(render::UiVertex, u), "ImDrawVert layout");
static_assert(offsetof(ImDrawVert, col) == offsetof(render::UiVertex, rgba), "ImDrawVert layout");

ImGuiRenderer::ImGuiRenderer(render::GlContext& context) : ui_(context) {
  ImGuiIO& io = ImGui::GetIO();
  io.BackendRendererName = "dynscope_render";
  unsigned char* pixels = nullptr;
  int width = 0, height = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &width, &height);
  const uint64_t texture = ui_.upload_texture(pixels, width, height);
  io.Fonts->SetTexID(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(texture)));
}

ImGuiRenderer::~ImGuiRenderer() {
  if (ImGui::GetCurrentContext() != nullptr) ImGui::GetIO().Fonts->SetTexID(ImTextureID{});
}

void* ImGuiRenderer::show_image(const render::Image& image) {
  if (image_texture_ == 0) {
    image_texture_ = ui_.upload_texture(image.rgba.data(), image.width, image.height);
  } else {
    ui_.update_texture(image_texture_, image.rgba.data(), image.width, image.height);
  }
  return reinterpret_cast<void*>(static_cast<intptr_t>(image_texture_));
}

void ImGuiRenderer::render(const ImDrawData* data) {
  if (data == nullptr) return;
  render::UiDrawData out;
  out.display_x = data->DisplayPos.x;
  out.display_y = data->DisplayPos.y;
  out.display_width = data->DisplaySize.x;
  out.display_height = data->DisplaySize.y;
  out.scale_x = data->FramebufferScale.x;
  out.scale_y = data->FramebufferScale.y;
  for (int n = 0; n < data->CmdListsCount; ++n) {
    const ImDrawList* list = data->CmdLists[n];
    render::UiDrawList l;
    l.vertices = reinterpret_cast<const render::UiVertex*>(list->VtxBuffer.Data);
    l.vertex_count = list->VtxBuffer.Size;
    l.indices = list->IdxBuffer.Data;
    l.index_count = list->IdxBuffer.Size;
    l.index_size = sizeof(ImDrawIdx);
    for (int c = 0; c < list->CmdBuffer.Size; ++c) {
      const ImDrawCmd& cmd = list->CmdBuffer[c];
      if (cmd.UserCallback != nullptr) {
        // ImGui's sentinel asks the renderer to restore its state (it does so per command).
        if (cmd.UserCallback != ImDrawCallback_ResetRenderState) cmd.UserCallback(list, &cmd);
        continue;
      }
      render::UiCommand u;
      u.clip_x0 = cmd.ClipRect.x;
      u.clip_y0 = cmd.ClipRect.y;
      u.clip_x1 = cmd.ClipRect.z;
      u.clip_y1 = cmd.ClipRect.w;
      u.texture = static_cast<uint64_t>(reinterpret_cast<intptr_t>(cmd.GetTexID()));
      u.index_offset = cmd.IdxOffset;
      u.index_count = cmd.ElemCount;
      l.commands.push_back(u);
    }
    out.lists.push_back(std::move(l));
  }
  ui_.render(out);
}

}  // namespace dynscope::app::viewer
