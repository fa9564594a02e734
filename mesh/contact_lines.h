// Contact lines: where another surface stands on, or passes through, a surface. Along such a line the radiosity of
// the surface is discontinuous in value (a D0 discontinuity: Heckbert 1992, "Discontinuity meshing for radiosity",
// section 3; Lischinski, Tampieri and Greenberg 1992, "Discontinuity meshing for accurate radiosity", section 3.1),
// so the initial meshing cuts the surface along it: no patch or element straddles it. docs/hierarchy.md,
// "Contact lines".
#pragma once

#include <vector>

#include "aarad/core/math.h"
#include "aarad/core/scene.h"

namespace aarad::mesh {

// A piece of line in a surface's plane, end points moved onto the plane.
struct ContactSegment {
  Vec3 a, b;
};

// Per surface of `scene` (indexed like scene.surfaces), the segments where faces of the other surfaces meet its
// plane, inside the surface's bounding box (grown by the tolerance):
// - an edge of a face of another plane whose two ends lie within kPlaneDistance x `diagonal` of the plane (a wall
//   standing on a floor);
// - where a face of another plane crosses the plane (ends beyond that distance on both sides: a leg sunk into
//   a floor), the chord between the two points where its outline meets the plane; a concave face that meets the
//   plane in more than two points gives the chords between consecutive crossings, and none when one of its
//   vertices lies on the plane (the pairing is then ambiguous).
// Faces of the surface's own plane (its own faces, coplanar surfaces and surfaces facing it from the same plane)
// give none, nor do the surface's own outline edges (edges of its faces that no other of its faces shares), which
// neighbours share. Other segments may lie on the surface's outline or outside it: the meshing keeps what crosses
// its inside.
// Repeated segments (an edge of two faces) are listed once. Candidates are found by intersecting boxes (CGAL's
// box_intersection_d), so the cost follows the number of faces near each surface, not surfaces x faces.
std::vector<std::vector<ContactSegment>> find_contact_lines(const Scene& scene, double diagonal);

}  // namespace aarad::mesh
