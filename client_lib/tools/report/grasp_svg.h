// A picture of one grasp as SVG: the object as flat-shaded polygons of a decimated mesh, drawn far
// to near, the hand's capsules (blocked ones darker) in front of or behind it, the palm and the
// phalanges without a capsule as context, and the contacts with their normals. One drawer for
// every picture: three axis views for `telegrasp-eval run --svg`, one readable view per object in
// the protocol report.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace telegrasp::sim {

/// What a grasp picture shows, all in the world frame.
struct GraspSnapshot {
  std::string title;
  const ObjectModel* model = nullptr;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  struct Capsule {
    Eigen::Vector3d a, b;
    double radius = 0;
    bool blocked = false;
  };
  std::vector<Capsule> capsules;
  struct Contact {
    Eigen::Vector3d p, n;  ///< Point on the object's surface and its unit normal, out of the object.
  };
  std::vector<Contact> contacts;
  /// Phalanges without a capsule (drawn lighter, for context): a segment from the joint along the
  /// display length, as thick as the finger's nearest capsule.
  struct Bone {
    Eigen::Vector3d a, b;
    double radius = 0;
  };
  std::vector<Bone> bones;
  struct Palm {
    Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();
    Eigen::Vector3d half_extent{0, 0, 0};
  };
  std::optional<Palm> palm;
};

/// Adds the hand of `rig` posed by X_WorldPalm and X_WorldPhalanx (rig order) to `snap`: a capsule
/// per capsule phalanx (`blocked`, per phalanx in rig order, may be empty: none blocked), a bone
/// per other phalanx, and the palm box.
void add_hand(GraspSnapshot& snap, const HandRig& rig, const Eigen::Isometry3d& X_WorldPalm,
              const std::vector<Eigen::Isometry3d>& X_WorldPhalanx, const std::vector<bool>& blocked);

/// The capsules and contacts of `hand` as they are now, and the object it holds (or `object`).
GraspSnapshot snapshot(const HandController& hand, const ObjectView& object, const std::string& title);

/// An orthographic view: screen right and up, and the direction toward the viewer, orthonormal
/// and right-handed (right x up = toward), in the world frame.
struct View {
  std::string name;
  Eigen::Vector3d right, up, toward;
};

/// The view from azimuth `azimuth_deg` (about world z, 0 = from +x) and `elevation_deg` above the
/// horizontal, world z up on the screen.
View orbit_view(double azimuth_deg, double elevation_deg);

/// The readable view of a grasp: of the 16 views from azimuths 0, 45, ..., 315 deg at elevations
/// 20 and 50 deg, the one that shows the most of the hand and of where it touches. Score: one
/// point per capsule sample (five along each capsule's axis, on its side toward the viewer) the
/// object does not hide, and four per contact that neither the object nor a capsule hides (so a
/// finger seen from the side, touching, beats one seen from behind); ties go to the earlier view
/// (azimuth first, 20 deg first).
View readable_view(const GraspSnapshot& snap);

/// A mesh to draw, with each triangle's unit normal taken from the surface it stands for.
struct DrawingMesh {
  TriangleMesh mesh;
  std::vector<Eigen::Vector3d> normals;  ///< Per triangle: the area-weighted mean of its source triangles' normals.
};

/// `mesh` with at most `max_triangles` triangles, by vertex clustering on a uniform grid (the
/// finest grid, shrinking by 20 % a step, that meets the budget; a cluster's vertex is the mean of
/// its vertices; collapsed triangles dropped, repeats merged). Each drawn triangle keeps the normal
/// of the original triangles it replaces, so one that folds over in the clustering still faces
/// and is shaded the way the surface does. Meant for drawing, not for metrics.
DrawingMesh decimate_for_drawing(const TriangleMesh& mesh, int max_triangles);

/// How a single-view picture is drawn.
struct PictureOptions {
  double width_px = 260, height_px = 240;
  int max_triangles = 1500;  ///< The object's mesh is decimated to this many triangles.
};

/// One view of the grasp as an inline `<svg>` element for an HTML page (no xmlns, no URL, no
/// script): the object's visible faces far to near, capsules that the object hides drawn before it
/// (and outlined dashed over it), the others after it; contacts as red dots with a normal tick,
/// hollow when behind the object. Elements carry classes: "object", "capsule" (plus "blocked"),
/// "capsule-hidden", "bone", "palm", "contact" (plus "hidden"), "normal".
std::string render_view_svg(const GraspSnapshot& snap, const View& view, const PictureOptions& options = {});

/// Top (x-y), front (x-z, from -y) and side (y-z, from +x) views as a self-contained SVG document.
std::string render_svg(const GraspSnapshot& snap);

}  // namespace telegrasp::sim
