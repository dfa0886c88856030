// The scene files of one split of a dataset directory written by `dynscope generate`.
#pragma once

#include <string>
#include <vector>

namespace dynscope {

/// One scene of a dataset split.
struct DatasetItem {
  std::string path;  ///< Full path of the scene file.
  std::string file;  ///< File name as listed in the manifest.
  int outcome = -1;  ///< Manifest label: 1/0 target touched the zone or not; −1 unlabelled.
};

/// A dataset directory's manifest, reduced to what training and evaluation need.
struct DatasetSplit {
  std::string dir;
  std::string scenario;            ///< Manifest "scenario".
  std::string split;               ///< "train", "val" or "test".
  std::vector<DatasetItem> items;  ///< In manifest order.
};

/// Reads DIR/manifest.json and returns the files of `split` ("all": every scene, in the order
/// train, val, test; for a dataset generated apart as a held-out set). Throws
/// ValueError("split", ...) for a split other than train/val/test/all, IoError if the manifest
/// is missing or unreadable, FormatError naming the field for a malformed manifest or a listed file
/// that does not exist.
DatasetSplit read_dataset_split(const std::string& dir, const std::string& split);

/// At most `max_scenes` scenes of `split`, evenly spaced over it (item ⌊i·M/max_scenes⌋ for
/// i < max_scenes, in order; M = its size), e.g. a sample of the training split to set beside the
/// validation split's numbers. A split of at most `max_scenes` scenes is returned as it is;
/// otherwise `split` becomes "<split>, N of M evenly spaced". Throws ValueError("max_scenes") for
/// max_scenes < 1.
DatasetSplit evenly_spaced_sample(const DatasetSplit& split, int max_scenes);

/// The scenes of `split` in every directory of `dirs`, one directory after the other, as one
/// split (e.g. the seven Physion-like scenarios evaluated as one set); with `max_scenes` > 0 at
/// most that many per directory (evenly_spaced_sample of each). One directory gives exactly what
/// read_dataset_split and evenly_spaced_sample give. Several: `dir` and `scenario` list theirs
/// joined by ", " (scenarios once each), and `split` is named `split` (e.g. "val"), or
/// "<split>, N of M evenly spaced per directory" when scenes were left out (N, M over all
/// directories). Throws like read_dataset_split,
/// ValueError("max_scenes") for max_scenes < 0, and ValueError("data") for no directory, a
/// directory named twice or a scene file name found in two directories (evaluations are matched
/// by file name).
DatasetSplit read_dataset_splits(const std::vector<std::string>& dirs, const std::string& split,
                                 int max_scenes = 0);

}  // namespace dynscope
