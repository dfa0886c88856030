// Architecture configuration of the dynamics model: plain data with a JSON round trip (no torch).
#pragma once

#include <string>

namespace dynscope {

/// Which layer fills each block of the U-Net: the paper's PointConv, the DPI-style GNN baseline,
/// or the non-object-centric baseline (one PointConv over plain kNN, no object/relational split).
enum class ModelKind { kPointConv, kGnn, kFlat };
/// What the network predicts per point: acceleration (p̂ = p + v + â) or velocity (p̂ = p + v̂).
enum class TargetMode { kAcceleration, kVelocity };
/// Model input: surface point clouds, or mesh vertices with the interaction-point relational path.
enum class InputMode { kPoints, kMesh };

/// "pointconv" | "gnn" | "flat"; parse throws ValueError("model", ...) on anything else.
std::string to_string(ModelKind kind);
ModelKind parse_model_kind(const std::string& name);
/// "acc" | "vel"; parse throws ValueError("target", ...) on anything else.
std::string to_string(TargetMode mode);
TargetMode parse_target_mode(const std::string& name);
/// "points" | "mesh"; parse throws ValueError("input", ...) on anything else.
std::string to_string(InputMode mode);
InputMode parse_input_mode(const std::string& name);

/// The one rule of which levels of the U-Net relate objects: none without objects (the flat
/// baseline); level 0 always; the levels below it only for point input without
/// relational_top_only (mesh input relates objects through interaction points at level 0 only).
/// ModelConfig::has_relational and the hierarchy's relational lists both follow it.
bool relates_objects_at(int level, bool object_centric, bool point_input, bool relational_top_only);

/// Everything needed to rebuild a model's architecture; stored as JSON inside every checkpoint.
/// Levels: level 0 holds the input points, level l ≥ 1 is level l−1 grid-downsampled per object
/// with voxel edge voxel·growth^(l−1); the relational radius at level l is radius·growth^l.
struct ModelConfig {
  ModelKind kind = ModelKind::kPointConv;
  TargetMode target = TargetMode::kAcceleration;
  InputMode input = InputMode::kPoints;
  int width = 32;              ///< C: feature channels at level 0.
  double width_growth = 2.0;   ///< Channels at level l = round(C·width_growth^l); 1 keeps C.
  int levels = 4;              ///< Hierarchy levels including the input level (encoder and decoder
                               ///< each have levels−1 resampling blocks).
  int bottleneck_blocks = 3;   ///< Interaction blocks at the coarsest level.
  int stem_blocks = 0;         ///< Interaction blocks at level 0 before the first downsampling
                               ///< (the paper has none; useful for mesh input, whose only
                               ///< relational convs run at level 0).
  int c_mid = 16;              ///< Output width of the PointConv WeightNet h.
  int k = 16;                  ///< Neighbours of object (and flat) convolutions.
  int k_relational = 16;       ///< Neighbours of relational convolutions before the radius filter.
  int pos_channels = 8;        ///< Width of the positional embedding e(p_i − p_0).
  int bottleneck_divisor = 4;  ///< Conv units run at out/divisor channels between 1×1 linears.
  double voxel = 0.075;        ///< Voxel edge of level 1 (scene units).
  double radius = 0.1;         ///< Relational radius at level 0 (scene units).
  double growth = 1.5;         ///< Voxel and radius factor per level.
  bool layer_norm = true;      ///< LayerNorm inside every conv unit; false: no normalisation.
  double interaction_threshold = 0.1;  ///< Mesh input: face-to-face interaction distance.
  int interaction_lattice = 3;         ///< Mesh input: samples per face edge when pairing faces.
  /// Mesh input: > 0 samples a face whose longest edge exceeds interaction_lattice × this with
  /// more subdivisions, at most this far apart along its edges (the paper samples faces
  /// uniformly; sparse meshes have large faces). 0: interaction_lattice on every face.
  double interaction_spacing = 0.0;
  /// Relational units only at level 0 (the paper's U-Net for meshes, its supplement: no relational
  /// reasoning between downsampled objects); mesh input always is so. false: every level of a
  /// points model has one. With true, a points model on mesh vertices is the paper's mesh U-Net
  /// without face reasoning (relations from the vertices within the radius).
  bool relational_top_only = false;
  /// Static bodies (mass 0) are given, not predicted: their points are inputs like any other but
  /// stay where they are (p̂(t+1) = p(t), PointState::static_points) and training leaves them out
  /// of the loss, each scene's loss being the mean over its moving points. false: every point is
  /// predicted and in the loss (the paper's formulation and every model trained before it).
  bool hold_static = false;

  /// The paper's Physion scale (voxel 0.075, radius 0.1) or Kubric scale (0.3, 0.4); `name` is
  /// "physion" or "kubric", anything else throws ValueError("scale", ...).
  static ModelConfig preset(const std::string& name);

  /// Channels of the features living at `level`.
  int channels(int level) const;
  /// Voxel edge used to build `level` (0 for level 0, whose points are the input).
  double voxel_at(int level) const;
  /// Relational radius at `level`.
  double radius_at(int level) const;

  /// Throws ValueError naming the first field out of range.
  void validate() const;
  /// Whether the blocks at `level` have a relational unit (none in the flat baseline).
  bool has_relational(int level) const;

  /// Compact JSON object with every field (hold_static and relational_top_only only when set, so
  /// that the configurations of models without them stay byte-identical to those written before
  /// they existed).
  std::string to_json() const;
  /// Parses JSON written by to_json(); missing fields keep their defaults. Throws FormatError
  /// (`source`, field, ...) on malformed JSON, wrong types or unknown enum names, and on values
  /// that fail validate().
  static ModelConfig from_json(const std::string& text, const std::string& source = "config");
};

}  // namespace dynscope
