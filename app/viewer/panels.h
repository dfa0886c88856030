// The viewer's panels: each draws one section from the ViewerState and returns what the user
// asked for as actions, which ViewerApp applies after drawing (Dear ImGui examples style).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "app/viewer/initial_state_edit.h"
#include "app/viewer/viewer_state.h"

namespace dynscope::app::viewer {

/// One change a panel asks of the state; it may throw (the error becomes the popup).
using Action = std::function<void(ViewerState&)>;

/// What the panels asked for during one frame, applied in order after drawing.
struct Actions {
  std::vector<Action> list;
  std::string screenshot;  ///< Non-empty: write a PNG of the next frame here.
  void add(Action a) { list.push_back(std::move(a)); }
};

/// Widget state that lives only in the UI (text fields, what-if fields): not viewer state.
struct PanelFields {
  std::string open_path;
  std::string checkpoint;
  std::string compare;
  std::string view_path = "view.json";
  std::string screenshot_path = "screenshot.png";
  ObjectEdit edit;
  int edit_object = -1;            ///< Object index the edit fields were filled from.
  uint64_t edit_generation = 0;    ///< Generation the edit fields belong to.
  uint64_t synced_generation = 0;  ///< Generation the text fields were last filled from.
  int explain_target = 0;          ///< ExplainTarget chosen in the Explain panel.
};

void draw_files_panel(const ViewerState& state, PanelFields& fields, Actions& out);
void draw_display_panel(const ViewerState& state, Actions& out);
void draw_rollout_panel(const ViewerState& state, Actions& out);
void draw_model_panel(const ViewerState& state, PanelFields& fields, Actions& out);
/// Divergence, explanation and attribution colours of the shown rollout (needs a checkpoint).
void draw_explain_panel(const ViewerState& state, PanelFields& fields, Actions& out);
/// Object table, plus the what-if editor when a checkpoint is in use.
void draw_objects_panel(const ViewerState& state, PanelFields& fields, Actions& out);
void draw_contacts_panel(const ViewerState& state, Actions& out);
void draw_levels_panel(const ViewerState& state, Actions& out);
void draw_inspector_panel(const ViewerState& state, Actions& out);
/// The bottom strip: transport, frame slider, speed, and the error strip with a rollout.
void draw_timeline_panel(const ViewerState& state, Actions& out);

}  // namespace dynscope::app::viewer
