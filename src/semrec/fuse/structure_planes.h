// Large planes of the room, for telling structure from things: a wall vote
// counts only on a large vertical plane, a floor vote only on the lowest large
// horizontal plane, a ceiling vote only on the highest. A 2D model calls the
// lower part of a chair floor and a table against the wall wall; an RGB-D map
// knows where the floor and the walls actually are.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "semrec/core/label_map.h"
#include "semrec/fuse/voxel.h"

namespace semrec::fuse {

// StructureGeometry (which plane a structure class lives on) and the
// footprint of one object of a class are label-set data (core/label_map.h,
// data/labels).

struct StructurePlaneOptions {
  /// Points within this distance of a plane lie on it (a voxel and some depth
  /// noise).
  double tolerance_m = 0.06;
  /// Each plane's own tolerance: tolerance_sigmas x the robust spread
  /// (1.4826 x MAD) of its points' distances to it, between min_tolerance_m
  /// and tolerance_m. A floor is flat and seen edge-on by nothing, so its
  /// voxels lie within a centimetre of it where depth is good; a voxel 3-6 cm
  /// up holds the foot of a sofa or a cabinet that views called floor at the
  /// contact. A wall measured as well is as thin; one seen at a grazing angle
  /// or after drift keeps the 6 cm.
  double tolerance_sigmas = 4.0;
  double min_tolerance_m = 0.025;
  /// A plane must hold at least this much of its class's surface (points x
  /// voxel area).
  double min_area_m2 = 1.0;
  /// A wall's points span at least this height (5th to 95th percentile along
  /// up): the side of a table is vertical and can be large, but low. Walls
  /// are sometimes seen only below the furniture's top or as low partitions.
  /// (7-Scenes chess's "walls", 0.82 and 0.88 m tall, are the fronts of base
  /// cabinets: min_top_surface_share tells those apart.)
  double min_wall_height_m = 0.7;
  /// Vertical planes: normals within this angle of horizontal.
  double max_wall_tilt_deg = 10.0;
  /// A point more than a wall's tolerance and at most this far behind it is
  /// inside or on top of it (BehindWall; 0: off); a furniture front's top
  /// reaches this + 0.2 m behind the front (TakeFurnitureFronts,
  /// OnTopOfFront). Further, on Bonn crowd's walls (depth layers 47 cm deep)
  /// a wall's band passed for a front with a top.
  double max_front_distance_m = 0.6;
  /// A point on a vertical plane more than 1.5 x tolerance_m and at most
  /// this far in front of a larger parallel wall is furniture, not wall
  /// (OnStructure), the front of a worktop (62-65 cm deep, kitchen 4's
  /// counter front 0.65 m before the wall) included. 0 turns it off.
  double max_furniture_depth_m = 0.75;
  /// A vertical plane with a horizontal surface behind it at its top (within
  /// max_front_distance_m + 0.2 m behind it, 30 cm deep or more) along at
  /// least this share of its length is the front of furniture, not a wall:
  /// no view sees the top of a wall (it meets the ceiling), but it sees a
  /// counter top over the cabinets a 2D model calls wall (7-Scenes chess:
  /// the red base cabinets, 0.88 m tall). 0 or more than 1: off.
  double min_top_surface_share = 0.2;
  /// A voxel whose own surface turns more than this from a plane's normal is
  /// not on the plane (OnStructure's `surface_axis`): the side of a shelf or a
  /// board running into the wall lies within a voxel of the wall's plane, and
  /// a 2D model calls the part near the wall wall in every view. >= 90: off.
  double max_surface_tilt_deg = 45.0;
  /// cos(max_surface_tilt_deg); 0 when off (>= 90): the least |cos| between
  /// a surface's axis and a plane's normal for the surface to lie along it.
  double MinSurfaceFacing() const;
  /// ... when the voxel's point normals agree on an axis: its share of their
  /// scatter at least this (VoxelEvidence::SurfaceAxis; a voxel holding a
  /// corner of the wall and a board has none and counts as on the plane).
  double min_normal_agreement = 0.6;
  /// ... and at least this many of its points have a normal (one or two
  /// pixels' normals agree with themselves).
  int min_normal_points = 10;
  /// At most this many vertical planes per class.
  int max_planes = 16;
  /// RANSAC hypotheses per vertical plane.
  int ransac_iterations = 300;
  uint64_t seed = 1;

  void Check() const;
};

struct StructurePlane {
  /// The class it holds (set by the caller).
  uint16_t class_id = 0;
  StructureGeometry geometry = StructureGeometry::kNone;
  /// normal . p = offset (world frame).
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
  /// Points (voxels) of the class on it.
  size_t support = 0;
  /// How close to it counts as on it (0: the options' tolerance_m).
  double tolerance_m = 0.0;
  /// Vertical planes: the normal faces the cameras that saw it (set by
  /// FindStructurePlanes from the views; OrientToInterior leaves it).
  bool oriented = false;
  /// Vertical planes: the horizontal direction along the plane and the 10 cm
  /// stretches along it its points cover (at any height), sorted.
  Eigen::Vector3d along = Eigen::Vector3d::Zero();
  std::vector<int64_t> along_bins;
  /// Vertical planes: the height (along up) below which 95 % of its points
  /// lie.
  double top_m = 0.0;

  bool Covers(const Eigen::Vector3d& p) const;
  /// Its own tolerance_m, else the options'.
  double Tolerance(const StructurePlaneOptions& options) const {
    return tolerance_m > 0.0 ? tolerance_m : options.tolerance_m;
  }
};

/// Planes of `geometry` among `points` (one per voxel of area
/// `voxel_area_m2`, all voting for the class): vertical planes by sequential
/// RANSAC with the plane containing `up`, floor/ceiling as the lowest/highest
/// height (along `up`) holding enough points. Empty when none is large enough.
/// `towards_camera` (parallel to `points`, or empty; zero: unknown): the
/// direction the points were seen from; a vertical plane then holds the
/// points seen from one side only and faces them (`oriented`).
/// `low_planes` (may be null) receives the vertical planes lower than
/// min_wall_height_m (candidates for furniture fronts, not walls).
std::vector<StructurePlane> FindStructurePlanes(
    const Cloud& points, StructureGeometry geometry,
    const Eigen::Vector3d& up_world, double voxel_area_m2,
    const StructurePlaneOptions& options,
    const std::vector<Eigen::Vector3f>& towards_camera = {},
    std::vector<StructurePlane>* low_planes = nullptr);

/// True when `p` lies within the tolerance of one of `planes`.
bool OnAnyPlane(const Eigen::Vector3f& p,
                const std::vector<StructurePlane>& planes, double tolerance_m);

/// Turns vertical planes' normals towards the room (those not `oriented`
/// by their views): the side most of `scene`
/// (every voxel of the map) lies on, counting only points within 3 m of the
/// plane along stretches it covers.
void OrientToInterior(const Cloud& scene, double tolerance_m,
                      std::vector<StructurePlane>* planes);

/// Moves out of `planes` the vertical ones that are the front of furniture
/// (see StructurePlaneOptions::min_top_surface_share; `scene`: every voxel
/// of the map) and returns them. Planes must be oriented (OrientToInterior).
/// `towards_camera` (parallel to `scene`, or empty: not checked): the
/// direction each point was seen from; only surfaces seen from above count
/// (a worktop seen over the front's top edge, not the top of a shelf in the
/// next room seen through a doorway).
std::vector<StructurePlane> TakeFurnitureFronts(
    const Cloud& scene, const Eigen::Vector3d& up_world,
    const StructurePlaneOptions& options, std::vector<StructurePlane>* planes,
    const std::vector<Eigen::Vector3f>& towards_camera = {});

/// Like OnAnyPlane, but a point standing in front of a larger parallel wall
/// (on the room's side, more than 1.5 x tolerance_m and at most
/// max_furniture_depth_m from it, along a stretch of it seen at some height)
/// is not on a wall, even where a smaller plane passes through it: RANSAC
/// fits a plane through a chair's back that views called wall and a strip of
/// the wall beyond it; no wall stands a hand's width in front of another. A
/// pilaster or a wall that steps out by 9-75 cm is set aside too: its voxels
/// stay wall where no other class has evidence and no thing claims them.
/// Planes must be oriented (OrientToInterior). Within `near_scale` x a
/// plane's tolerance (its own, else the options') counts as on it.
/// `surface_axis` (may be null: unknown): the normal axis of the surface at
/// `p`; a plane it turns more than max_surface_tilt_deg from does not hold
/// `p`.
bool OnStructure(const Eigen::Vector3f& p,
                 const std::vector<StructurePlane>& planes,
                 const StructurePlaneOptions& options, double near_scale = 1.0,
                 const Eigen::Vector3f* surface_axis = nullptr);

/// True when `p` lies behind an oriented wall (more than its tolerance and
/// at most max_front_distance_m behind it, along a stretch it covers) and
/// not in front of a wall facing the other way (the other face of an interior
/// wall: then it is in the next room): the top of a partition, the inside of
/// a wall.
bool BehindWall(const Eigen::Vector3f& p,
                const std::vector<StructurePlane>& planes,
                const StructurePlaneOptions& options);

/// True when `p` lies where a furniture front's top surface is (a worktop):
/// behind the oriented front by at most max_front_distance_m + 0.2 m, from
/// 10 cm below to 15 cm above its top (top_m), along a stretch it covers.
bool OnTopOfFront(const Eigen::Vector3f& p, const StructurePlane& front,
                  const Eigen::Vector3d& up_world,
                  const StructurePlaneOptions& options);

}  // namespace semrec::fuse
