// Garment panels (cold tier): pattern pieces turned into particles, springs and triangles.
//
// Two ways to author a panel, both from the seeds:
//   - a 0/1 mask on a square grid (seed 000 section 1.4): '1' = a particle at that grid point. Springs join grid
//     neighbours by the offsets of the hang scene (structural, shear, bend);
//   - an outline polygon (seed 004 section 1): its bounding box is filled with evenly spaced points, the points
//     outside are dropped, the rest (plus points sampled along the outline) are triangulated with Bowyer-Watson
//     Delaunay; a stretch spring on every triangle edge and a bending "cross" spring across every shared edge
//     (seed 001).
// Panels are appended to a GarmentAssembly, a growing list of particles, springs and triangles, so several
// panels make one cloth. Panels are joined by seam springs (SpringKind::seam): the T-shirt builder sews its
// front and back panels; sew_by_arc_length() sews any two boundary polylines. The assembly feeds cook_cloth()
// unchanged (inverse_masses(), edges) plus initial_state() for the simulation.
//
// Frames: a panel is authored in 2D (u, v) coordinates, metres, and placed in 3D by a PanelFrame (an origin
// and two orthonormal in-plane axes), so a panel can stand vertically. Triangles are counter-clockwise seen
// from the panel normal u x v (the cooked cloth's convention).
//
// One header per stage, each with its .cpp of the same name: garment_assembly (the assembly, the frame, the springs of
// a triangle mesh), mask_panel, tshirt, outline_panel, delaunay (its mesher) and pattern_seams (sewing two polylines).
// This header includes them all.
#pragma once

#include "drape/delaunay.hpp"
#include "drape/garment_assembly.hpp"
#include "drape/mask_panel.hpp"
#include "drape/outline_panel.hpp"
#include "drape/pattern_seams.hpp"
#include "drape/tshirt.hpp"
