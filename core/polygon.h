// Planar polygon utilities. A polygon is a closed loop of vertices without the first repeated.
#pragma once

#include "aarad/core/math.h"

#include <array>
#include <cstddef>
#include <span>
#include <vector>

namespace aarad {

// Newell's vector area: half the sum of v_i x v_{i+1}. Its length is the area of a planar polygon and
// its direction the normal for which the vertices run counter-clockwise.
Vec3 vector_area(std::span<const Vec3> polygon);
double area(std::span<const Vec3> polygon);
// Unit normal (counter-clockwise seen from its tip); (0, 0, 0) for a polygon of zero area.
Vec3 normal(std::span<const Vec3> polygon);
// Area centroid of a planar polygon (the vertex mean when the area is zero).
Vec3 centroid(std::span<const Vec3> polygon);
// The plane through the centroid with the Newell normal.
Plane plane_of(std::span<const Vec3> polygon);
// Largest distance of a vertex from plane_of(polygon).
double planarity_deviation(std::span<const Vec3> polygon);
// Diagonal of the axis-aligned bounding box of the points (0 for none).
double box_diagonal(std::span<const Vec3> points);

// 2D: signed area (positive counter-clockwise, y up), convexity and simplicity. Convexity and simplicity
// are decided with exact predicates (core/predicates.h), so collinear and touching cases are reported
// consistently.
double signed_area(std::span<const Vec2> polygon);
bool is_convex(std::span<const Vec2> polygon);  // strictly or with collinear vertices; either winding
bool is_simple(std::span<const Vec2> polygon);  // no two non-adjacent edges touch, adjacent ones meet only at their shared vertex
// Crossing-number test of a point against a simple polygon, each crossing decided by an exact orientation
// predicate: a point off the boundary is classified exactly, however near the boundary it lies. A point on the
// boundary may go either way, so callers ask about points off it (a triangle's centroid, a face's area centroid).
bool contains(std::span<const Vec2> polygon, const Vec2& p);

// Ear clipping of a simple polygon given counter-clockwise in 2D: appends index triples (counter-clockwise) to
// `triangles`. Vertices where the boundary goes straight on are clipped like any other ear; the resulting
// zero-area triangles are left for the caller to drop.
void ear_clip(std::span<const Vec2> polygon, std::vector<std::array<std::size_t, 3>>& triangles);
// The intersection of two convex polygons, both counter-clockwise (Sutherland-Hodgman, in doubles), into `out`
// (fewer than 3 vertices, or points on a line, where they do not overlap), with `scratch` as room (no allocation
// once both have grown); and its area. `b` needs 3 vertices or more, and `out` and `scratch` must be other vectors
// than `a` and `b`.
void convex_intersection(std::span<const Vec2> a, std::span<const Vec2> b, std::vector<Vec2>& out,
                         std::vector<Vec2>& scratch);
double convex_intersection_area(std::span<const Vec2> a, std::span<const Vec2> b);

// The axis that project_to_2d drops for normal `n`: its largest component (0, 1, 2 for x, y, z; ties to the
// lower axis).
int dropped_axis(const Vec3& n);
// Projects a planar 3D polygon onto the coordinate plane most orthogonal to `n` (dropping dropped_axis(n)),
// keeping the winding seen from the tip of n counter-clockwise in 2D.
void project_to_2d(std::span<const Vec3> polygon, const Vec3& n, std::span<Vec2> out);

}  // namespace aarad
