// The T-shirt (seed 000): two identical mask panels sewn along the shoulders, the sides and under the sleeves.
#pragma once

#include <cstdint>
#include <vector>

#include "drape/garment_assembly.hpp"
#include "drape/mask_panel.hpp"

namespace drape {

/// What the user chooses for the T-shirt (cold tier). Ranges are checked by build_tshirt.
///
/// Frame (the body frame of default_body() in colliders.hpp): y up, the wearer faces +z, origin at the torso
/// centre. The flat shirt pattern (per panel, metres, each rounded to whole cells): a body 0.48 wide and 0.68
/// tall (hem at shoulder_y - 0.68), two short sleeves 0.20 long and 0.18 deep along the shoulder line (a T
/// shape 0.88 wide: the arms of default_body() are in a T-pose to match), and an elliptical neck opening 0.20
/// wide and 0.08 deep. Mask cell (row, column) is the point x = (column - m) h, y = shoulder_y - row h, with
/// h = 1 / cells_per_metre and m the centre column. The front panel lies in the plane z = +gap / 2 with
/// normal +z, the back panel in z = -gap / 2 with normal -z; both come from the same mask (identical panels;
/// the back's columns run the other way, so its normal faces out too).
struct TShirtParams {
    /// Grid resolution, cells per metre (10..1000). 35 is the seed's resolution: 2 x 504 = 1,008 particles;
    /// 360 gives about 101k particles (the count grows as about 0.78 r^2).
    float cells_per_metre = 35.0f;
    float total_mass = 0.15f; ///< kg (0.001..10), spread evenly over both panels
    float shoulder_y = 0.33f; ///< height of the shoulder line (top row), m, in the body frame (-10..10)
    /// Distance between the panels, m (0.001..2). The default clears default_body() (torso 0.20 m deep, hips
    /// 0.22 m) by 2 cm on each side, so the shirt starts outside the body and its seams close it.
    float gap = 0.26f;
    /// Rest length of a seam spring as a fraction of the grid spacing (0.01..2; cook_cloth refuses 0). The
    /// seams start `gap` long and pull the panels together to this length: a closed seam leaves a gap this wide
    /// (0.5 h here; the built-in scene uses 0.05 h and sews the seams shut at SimulationParams::sewing_speed).
    float seam_rest_ratio = 0.5f;
    /// Exact mirror symmetry (mirror_symmetry.hpp; docs/garments.md, "Mirror-exact sums"): both panels placed from
    /// their centre column, so the halves start as exact mirror images, and the cooked cloth made mirror-exact
    /// (make_mirror_exact) so that they stay so through sewing, bending, body contact, the strain limit and
    /// self-collision (explicit solver; the implicit solver's sweeps are not mirror-ordered). On by default since
    /// 2026-12-07, when self-collision began to move particles sewn together as one point (before, its pushes held
    /// the exactly folded shoulder seam of the hem-push test 0.347 long against the limit's 0.3).
    bool mirror_exact = true;
};

/// Which part of the pattern a sewn front particle lies on.
enum class SeamPart : std::uint8_t { shoulder, side, underarm };

struct TShirtBuild {
    GarmentAssembly assembly;
    MaskPanel mask;                        ///< the panel mask at this resolution
    MaskPanelBuild front, back;            ///< where each panel landed (front first)
    float spacing = 0.0f;                  ///< h, m
    std::vector<std::uint32_t> seam_edges; ///< indices into assembly.edges of the seam springs
    std::vector<SeamPart> seam_part;       ///< per seam edge, the part of the pattern it closes
    /// Each particle's mirror twin (x -> -x): the particle of the same panel and row in the mirrored column.
    std::vector<std::uint32_t> mirror;
};

/// The T-shirt mask at `cells_per_metre` (10..1000), symmetric left-right. Throws InvalidInput.
MaskPanel tshirt_mask(float cells_per_metre);

/// Builds the two panels and the seams: one seam spring (SpringKind::seam, rest seam_rest_ratio * h) joins
/// every front particle on the shoulder line (top row, including the sleeve tops), the sides of the body
/// (outermost particle of each row below the sleeves, down to the hem) and the underside of the sleeves (the
/// bottom row of each sleeve, out to the cuff) to the back particle at the same (x, y). Not sewn: the neck
/// opening, the hem (waist) and the sleeve openings (cuffs), except their end particles where they meet a
/// seam. Throws InvalidInput.
TShirtBuild build_tshirt(const TShirtParams& params);

} // namespace drape
