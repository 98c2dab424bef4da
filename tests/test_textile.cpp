// Textile verification, cheap versions (the full tables: bench/textile, `drape_textile`, docs/fabric.md
// "Verification"): the heavy-elastica reference against closed forms, uniaxial tension at one spacing within 1%,
// the Peirce cantilever at 10 mm within 5%.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "elastica.hpp"
#include "harness.hpp"

using namespace drape;
using namespace drape::textile;

TEST(Elastica, SmallDeflectionMatchesEulerBernoulli) {
    // l / c = 0.3: tip deflection q l^4 / (8 B) = l (l/c)^3 / 8; the elastica's correction is O((deflection/l)^2).
    const double B = 2e-6, w = 0.15, q = w * 9.81, c = bending_length(B, w);
    const double l = 0.3 * c;
    const ElasticaShape e = solve_elastica(l, c);
    const double expected = small_deflection_tip(q, l, B);
    EXPECT_NEAR(-e.tip_y() / expected, 1.0, 1e-4);
    EXPECT_NEAR(e.kappa0, q * l * l / (2.0 * B), 1e-4 * e.kappa0); // clamp moment q l^2 / 2
}

TEST(Elastica, LargeDeflectionBalancesMomentsAndStaysInextensible) {
    // l / c = 3: the tip drops far (about 70 deg chord); the clamp moment B phi'(0) must equal the weight's moment
    // about the clamp, q * integral of x ds, and the arc length must stay l.
    const double c = 0.02, l = 0.06, B = 1.0, q = B / (c * c * c);
    const ElasticaShape e = solve_elastica(l, c);
    double moment = 0.0, arc = 0.0;
    for (std::size_t k = 1; k < e.s.size(); ++k) {
        const double ds = e.s[k] - e.s[k - 1];
        moment += q * 0.5 * (e.x[k] + e.x[k - 1]) * ds;
        arc += std::hypot(e.x[k] - e.x[k - 1], e.y[k] - e.y[k - 1]);
    }
    EXPECT_NEAR(B * e.kappa0 / moment, 1.0, 1e-5);
    EXPECT_NEAR(arc / l, 1.0, 1e-6);
    EXPECT_GT(e.chord_angle(), 1.0); // well past small deflection
    // The inverse: the chord angle gives back c.
    EXPECT_NEAR(elastica_bending_length(l, e.chord_angle()) / c, 1.0, 1e-6);
}

TEST(Elastica, PeirceRelationApproximatesItNearTheAstmAngle) {
    // ASTM D1388 reads c = l / 2 at 41.5 deg from Peirce's relation; the exact elastica agrees to a few per cent.
    const double theta = 41.5 * std::numbers::pi / 180.0;
    EXPECT_NEAR(peirce_bending_length(1.0, theta), 0.5, 0.01);
    EXPECT_NEAR(elastica_bending_length(1.0, theta) / peirce_bending_length(1.0, theta), 1.0, 0.02);
}

class TextileTension : public ::testing::TestWithParam<bool> {};

TEST_P(TextileTension, StrainIsLoadOverStiffnessWithinOnePercent) {
    TensionCase c;
    c.fabric = textile_fabric("cotton_shirting");
    c.length = 0.1;
    c.spacing = 0.01;
    c.along_v = GetParam();
    const TensionResult r = run_tension(c);
    EXPECT_TRUE(r.settle.settled);
    EXPECT_NEAR(r.measured_strain / r.expected_strain, 1.0, 0.01)
        << "measured " << r.measured_strain << " expected " << r.expected_strain;
}

INSTANTIATE_TEST_SUITE_P(Directions, TextileTension, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "v" : "u"; });

class TextileCantilever : public ::testing::TestWithParam<bool> {};

TEST_P(TextileCantilever, PeirceBendingLengthWithinFivePercentAt10mm) {
    CantileverCase c;
    c.fabric = textile_fabric("denim");
    c.along_v = GetParam();
    const double cin = bending_length(c.along_v ? c.fabric.bend_v : c.fabric.bend_u, c.fabric.density);
    c.overhang = 2.0 * cin; // ASTM's 41.5 deg
    c.spacing = 0.01;
    const CantileverResult r = run_cantilever(c);
    EXPECT_TRUE(r.settle.settled);
    EXPECT_NEAR(r.c_elastica / r.c_input, 1.0, 0.05) << "theta " << r.theta << " reference " << r.theta_reference;
    EXPECT_NEAR(r.c_peirce / r.c_input, 1.0, 0.05);
    EXPECT_LT(r.shape_error, 0.03);
}

INSTANTIATE_TEST_SUITE_P(Directions, TextileCantilever, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "v" : "u"; });
