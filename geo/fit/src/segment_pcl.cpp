// The segmentation stages that PCL does for us: statistical outlier removal, voxel grid,
// neighbourhoods for normals, Euclidean clustering and region growing. PCL's headers stay in
// this file; its types never leave it. PCL works in float: the points are tile-local, so float
// keeps them to a few micrometres.

// PCL's templates are instantiated here (PCL_NO_PRECOMPILE) rather than taken from its
// libraries' precompiled instances: the binary then needs no libpcl_segmentation, which pulls
// in libpcl_features and libpcl_ml, whose symbols every csgtile process had to bind at start.
#define PCL_NO_PRECOMPILE
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "csgtile/fit/segment.h"
#include "fit_internal.h"

namespace csgtile::fit {

namespace {

using kernel::Vec3;

// The finite ones of `n` points, the k-th point_of(k), as a PCL cloud, with their positions k.
template <class PointOf>
pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_of(std::size_t n, const PointOf& point_of,
                                             std::vector<std::uint32_t>& index) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->reserve(n);
  index.clear();
  index.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& p = point_of(k);
    // PCL works in float: coordinates beyond its range are as unusable as NaN.
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e30) continue;
    cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(p.z())));
    index.push_back(static_cast<std::uint32_t>(k));
  }
  cloud->width = static_cast<std::uint32_t>(cloud->size());
  cloud->height = 1;
  cloud->is_dense = true;
  return cloud;
}

// The finite points as a PCL cloud, with their input indices.
pcl::PointCloud<pcl::PointXYZ>::Ptr to_cloud(std::span<const Vec3> points,
                                             std::vector<std::uint32_t>& index) {
  return cloud_of(
      points.size(), [&](std::size_t k) -> const Vec3& { return points[k]; }, index);
}

// PCL's index lists (into the cloud) as lists of input indices, each ascending, empty ones
// dropped; ordered by size (largest first), ties by smallest index: deterministic.
std::vector<std::vector<std::uint32_t>> to_groups(const std::vector<pcl::PointIndices>& lists,
                                                  const std::vector<std::uint32_t>& index) {
  std::vector<std::vector<std::uint32_t>> out;
  for (const auto& list : lists) {
    if (list.indices.empty()) continue;
    std::vector<std::uint32_t> members;
    members.reserve(list.indices.size());
    for (auto k : list.indices) members.push_back(index[static_cast<std::size_t>(k)]);
    std::sort(members.begin(), members.end());
    out.push_back(std::move(members));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    if (a.size() != b.size()) return a.size() > b.size();
    return a.front() < b.front();
  });
  return out;
}

// The entries of `index` (one per point of `cloud`) of the points the statistical filter keeps,
// ascending: both remove_statistical_outliers.
std::vector<std::uint32_t> kept_by_filter(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud,
                                          std::vector<std::uint32_t> index,
                                          const OutlierOptions& options) {
  if (!options.enabled || cloud->size() <= static_cast<std::size_t>(options.neighbours) + 1) {
    return index;
  }
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  filter.setMeanK(options.neighbours);
  filter.setStddevMulThresh(options.std_ratio);
  pcl::Indices kept;
  filter.filter(kept);
  std::vector<std::uint32_t> out;
  out.reserve(kept.size());
  for (auto k : kept) out.push_back(index[static_cast<std::size_t>(k)]);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

std::vector<std::uint32_t> remove_statistical_outliers(std::span<const Vec3> points,
                                                       const OutlierOptions& options) {
  std::vector<std::uint32_t> index;
  auto cloud = to_cloud(points, index);
  return kept_by_filter(cloud, std::move(index), options);
}

std::vector<std::uint32_t> remove_statistical_outliers(std::span<const Vec3> points,
                                                       std::span<const std::uint32_t> subset,
                                                       const OutlierOptions& options) {
  std::vector<std::uint32_t> index;
  auto cloud = cloud_of(
      subset.size(), [&](std::size_t k) -> const Vec3& { return points[subset[k]]; }, index);
  return kept_by_filter(cloud, std::move(index), options);
}

std::vector<Vec3> voxel_downsample(std::span<const Vec3> points, const VoxelOptions& options) {
  std::vector<std::uint32_t> index;
  auto cloud = to_cloud(points, index);
  std::vector<Vec3> out;
  if (!(options.size > 0.0) || cloud->empty()) {
    for (auto i : index) out.push_back(points[i]);
    return out;
  }
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(cloud);
  const auto leaf = static_cast<float>(options.size);
  grid.setLeafSize(leaf, leaf, leaf);
  pcl::PointCloud<pcl::PointXYZ> filtered;
  grid.filter(filtered);
  out.reserve(filtered.size());
  for (const auto& p : filtered) out.emplace_back(p.x, p.y, p.z);
  return out;
}

std::vector<std::int32_t> detail::nearest_of(std::span<const Vec3> queries,
                                             std::span<const Vec3> targets) {
  std::vector<std::int32_t> out(queries.size(), -1);
  std::vector<std::uint32_t> index;
  auto cloud = to_cloud(targets, index);
  if (cloud->empty()) return out;
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  pcl::Indices found;
  std::vector<float> distances;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const Vec3& p = queries[q];
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e30) continue;
    const pcl::PointXYZ at(static_cast<float>(p.x()), static_cast<float>(p.y()),
                           static_cast<float>(p.z()));
    if (tree.nearestKSearch(at, 1, found, distances) == 1) {
      out[q] = static_cast<std::int32_t>(index[static_cast<std::size_t>(found[0])]);
    }
  }
  return out;
}

namespace {

// The normal of the face a point lies on, where its neighbourhood straddles an edge: of the
// planes through the point and two of its nearest neighbours (every pair of the ten nearest),
// the one most neighbours lie on (within 5 % of the neighbourhood's radius; ties: the smaller
// sum of squared distances), refined by principal components of those neighbours. `near`
// holds the neighbours' positions relative to the point, nearest first. Zero when no pair
// spans a plane.
Vec3 face_normal(std::span<const Vec3> near) {
  if (near.size() < 2) return Vec3::Zero();
  const double radius = near.back().norm();
  const double tol = 0.05 * radius;
  const std::size_t m = std::min<std::size_t>(near.size(), 10);
  Vec3 best_n = Vec3::Zero();
  std::size_t best_count = 0;
  double best_sum = INFINITY;
  for (std::size_t a = 0; a < m; ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      Vec3 n = near[a].cross(near[b]);
      const double len = n.norm();
      // Nearly collinear with the point: no plane.
      if (!(len > 0.2 * near[a].norm() * near[b].norm())) continue;
      n /= len;
      std::size_t count = 0;
      double sum = 0.0;
      for (const Vec3& q : near) {
        const double d = std::abs(n.dot(q));
        if (d <= tol) {
          ++count;
          sum += d * d;
        }
      }
      if (count > best_count || (count == best_count && sum < best_sum)) {
        best_count = count;
        best_sum = sum;
        best_n = n;
      }
    }
  }
  if (best_count < 2) return best_n;
  // Principal components of the point and the neighbours on that plane.
  Vec3 mean = Vec3::Zero();
  std::size_t used = 1;
  for (const Vec3& q : near) {
    if (std::abs(best_n.dot(q)) <= tol) {
      mean += q;
      ++used;
    }
  }
  mean /= static_cast<double>(used);
  Eigen::Matrix3d cov = mean * mean.transpose();  // the point itself, at the origin
  for (const Vec3& q : near) {
    if (std::abs(best_n.dot(q)) <= tol) cov += (q - mean) * (q - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return best_n;
  const auto& values = eig.eigenvalues();
  if (!(values(1) > 1e-4 * values(2))) return best_n;
  const Vec3 n = eig.eigenvectors().col(0);
  if (!n.allFinite()) return best_n;
  return n.normalized();
}

}  // namespace

void detail::normals_and_curvature(std::span<const Vec3> points, int neighbours,
                                   std::vector<Vec3>& normals, std::vector<double>& curvature,
                                   bool sharp) {
  normals.assign(points.size(), Vec3::Zero());
  curvature.assign(points.size(), 1.0 / 3.0);
  std::vector<std::uint32_t> index;
  auto cloud = to_cloud(points, index);
  if (cloud->size() < 3 || neighbours < 3) return;
  // PCL finds the neighbours; the principal components are ours, so that collinear and
  // duplicated neighbourhoods (two vanishing spreads) give no normal instead of an arbitrary one.
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  const int k = std::min<int>(neighbours, static_cast<int>(cloud->size()));
  pcl::Indices found;
  std::vector<float> distances;
  std::vector<Vec3> near;
  for (std::size_t q = 0; q < cloud->size(); ++q) {
    if (tree.nearestKSearch(static_cast<pcl::index_t>(q), k, found, distances) < 3) continue;
    const Vec3& centre = points[index[q]];
    Vec3 mean = Vec3::Zero();
    for (auto f : found) mean += points[index[static_cast<std::size_t>(f)]] - centre;
    mean /= static_cast<double>(found.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (auto f : found) {
      const Vec3 d = points[index[static_cast<std::size_t>(f)]] - centre - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (eig.info() != Eigen::Success) continue;
    const auto& values = eig.eigenvalues();
    if (!(values(2) > 0.0) || !(values(1) > 1e-4 * values(2))) continue;
    Vec3 n = eig.eigenvectors().col(0);
    if (!n.allFinite()) continue;
    if (sharp) {
      near.clear();
      for (auto f : found) {
        const Vec3 d = points[index[static_cast<std::size_t>(f)]] - centre;
        if (d.squaredNorm() > 0.0) near.push_back(d);
      }
      if (const Vec3 face = face_normal(near); face.squaredNorm() > 0.0) n = face;
    }
    normals[index[q]] = n.normalized();
    curvature[index[q]] =
        std::max(0.0, values(0)) / (std::max(0.0, values(0)) + values(1) + values(2));
  }
}

std::vector<Vec3> estimate_normals(std::span<const Vec3> points, const NormalOptions& options) {
  std::vector<Vec3> normals;
  std::vector<double> curvature;
  detail::normals_and_curvature(points, options.neighbours, normals, curvature, options.sharp);
  return normals;
}

std::vector<std::vector<std::uint32_t>> region_growing(std::span<const Vec3> points,
                                                       std::span<const Vec3> normals,
                                                       const RegionGrowingOptions& options,
                                                       std::span<const double> curvature) {
  std::vector<std::vector<std::uint32_t>> out;
  if (normals.size() != points.size() || (!curvature.empty() && curvature.size() != points.size()))
    return out;
  if (!options.enabled) {
    std::vector<std::uint32_t> all;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (points[i].allFinite()) all.push_back(static_cast<std::uint32_t>(i));
    }
    if (!all.empty()) out.push_back(std::move(all));
    return out;
  }
  if (options.neighbours < 3 || !(options.smoothness_deg > 0.0) || !(options.curvature > 0.0))
    return out;
  std::vector<double> computed;
  if (curvature.empty()) {
    std::vector<Vec3> unused;
    detail::normals_and_curvature(points, options.neighbours, unused, computed);
    curvature = computed;
  }
  // Only points with a normal take part: PCL would compare a zero normal at 90° to everything,
  // and a NaN one unpredictably. They stay outside every region.
  std::vector<std::uint32_t> index;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  auto cloud_normals = std::make_shared<pcl::PointCloud<pcl::Normal>>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const Vec3& n = normals[i];
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e30 || !n.allFinite() ||
        !(n.squaredNorm() > 0.25) || !std::isfinite(curvature[i])) {
      continue;
    }
    const Vec3 u = n.normalized();
    cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(p.z())));
    cloud_normals->push_back(pcl::Normal(static_cast<float>(u.x()), static_cast<float>(u.y()),
                                         static_cast<float>(u.z()),
                                         static_cast<float>(curvature[i])));
    index.push_back(static_cast<std::uint32_t>(i));
  }
  const long long min_points = std::max<long long>(1, options.min_points);
  if (static_cast<long long>(cloud->size()) < std::max<long long>(3, min_points)) return out;
  cloud->width = static_cast<std::uint32_t>(cloud->size());
  cloud->height = 1;
  cloud->is_dense = true;
  cloud_normals->width = cloud->width;
  cloud_normals->height = 1;
  cloud_normals->is_dense = true;
  auto tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> growing;
  growing.setSearchMethod(tree);
  growing.setNumberOfNeighbours(static_cast<unsigned int>(
      std::min<std::size_t>(static_cast<std::size_t>(options.neighbours), cloud->size())));
  growing.setMinClusterSize(
      static_cast<pcl::uindex_t>(std::min<long long>(min_points, std::numeric_limits<int>::max())));
  growing.setMaxClusterSize(static_cast<pcl::uindex_t>(std::numeric_limits<int>::max()));
  growing.setSmoothModeFlag(true);
  growing.setSmoothnessThreshold(
      static_cast<float>(options.smoothness_deg * std::numbers::pi / 180.0));
  growing.setCurvatureTestFlag(true);
  growing.setCurvatureThreshold(static_cast<float>(options.curvature));
  growing.setResidualTestFlag(false);
  growing.setInputCloud(cloud);
  growing.setInputNormals(cloud_normals);
  std::vector<pcl::PointIndices> regions;
  growing.extract(regions);
  return to_groups(regions, index);
}

std::vector<std::vector<std::uint32_t>> euclidean_clusters(std::span<const Vec3> points,
                                                           const ClusterOptions& options,
                                                           double* tolerance_used) {
  std::vector<std::uint32_t> index;
  auto cloud = to_cloud(points, index);
  if (cloud->empty()) return {};
  double tolerance = options.tolerance;
  if (!(tolerance > 0.0)) tolerance = 1.5 * detail::neighbour_reach(points, index, 0.9);
  if (!(tolerance > 0.0)) tolerance = 1e-3;
  if (tolerance_used != nullptr) *tolerance_used = tolerance;
  // Unsorted radius searches: the clusters do not depend on the order of neighbours.
  auto tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>(false);
  tree->setInputCloud(cloud);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> extraction;
  extraction.setClusterTolerance(tolerance);
  extraction.setMinClusterSize(static_cast<int>(std::max<long long>(1, options.min_points)));
  extraction.setMaxClusterSize(std::numeric_limits<int>::max());
  extraction.setSearchMethod(tree);
  extraction.setInputCloud(cloud);
  std::vector<pcl::PointIndices> clusters;
  extraction.extract(clusters);
  return to_groups(clusters, index);
}

}  // namespace csgtile::fit
