// PLY / PCD export of labelled points through PCL, written atomically.
#include "engine/io/point_export.h"

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <functional>

#include "engine/core/error.h"
#include "engine/io/temp_file.h"

namespace dynscope {
namespace {

pcl::PointCloud<pcl::PointXYZL> to_cloud(const Points& points,
                                         const std::vector<int32_t>& object_ids) {
  if (static_cast<size_t>(points.rows()) != object_ids.size()) {
    throw ValueError("object_ids", std::to_string(object_ids.size()) + " ids for " +
                                       std::to_string(points.rows()) + " points");
  }
  if (points.rows() == 0) throw ValueError("points", "no points to export");
  pcl::PointCloud<pcl::PointXYZL> cloud;
  cloud.resize(static_cast<size_t>(points.rows()));
  cloud.width = static_cast<uint32_t>(points.rows());
  cloud.height = 1;
  cloud.is_dense = points.allFinite();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const int32_t id = object_ids[static_cast<size_t>(i)];
    // The label field is unsigned in PCL; a negative id would come back as a huge number.
    if (id < 0) {
      throw ValueError("object_ids", "negative id " + std::to_string(id) + " at index " +
                                         std::to_string(i) + " cannot be stored as a label");
    }
    pcl::PointXYZL& p = cloud[static_cast<size_t>(i)];
    p.x = static_cast<float>(points(i, 0));
    p.y = static_cast<float>(points(i, 1));
    p.z = static_cast<float>(points(i, 2));
    p.label = static_cast<uint32_t>(id);
  }
  return cloud;
}

void write_atomically(const std::string& path, const char* format,
                      const std::function<int(const std::string&)>& write) {
  TempFile temp(path);
  int status = -1;
  try {
    status = write(temp.path());
  } catch (const pcl::PCLException& e) {
    throw IoError(path, std::string(format) + " write failed: " + e.detailedMessage());
  }
  if (status < 0) throw IoError(path, std::string(format) + " write failed");
  temp.commit();
}

}  // namespace

void export_points_ply(const std::string& path, const Points& points,
                       const std::vector<int32_t>& object_ids) {
  const pcl::PointCloud<pcl::PointXYZL> cloud = to_cloud(points, object_ids);
  // PLYWriter directly, to leave out PCL's non-standard "camera" element that
  // savePLYFileBinary adds and other PLY readers do not expect.
  write_atomically(path, "PLY", [&](const std::string& file) {
    pcl::PLYWriter writer;
    return writer.write(file, cloud, /*binary=*/true, /*use_camera=*/false);
  });
}

void export_points_pcd(const std::string& path, const Points& points,
                       const std::vector<int32_t>& object_ids) {
  const pcl::PointCloud<pcl::PointXYZL> cloud = to_cloud(points, object_ids);
  write_atomically(path, "PCD", [&](const std::string& file) {
    return pcl::io::savePCDFileBinary(file, cloud);
  });
}

}  // namespace dynscope
