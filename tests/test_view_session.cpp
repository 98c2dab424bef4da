// The viewer's model (app/view_session.cpp) without a window: changes the panels make are applied, unstable
// ones are compensated with more substeps or refused with a message (never an unstable step), rebuilds keep
// the motion and the pins, every pin can be unpinned, grabs pin and release.
#include <gtest/gtest.h>

#include <cmath>

#include "drape/errors.hpp"
#include "drape/stability.hpp"
#include "view_session.hpp"

using namespace drape;
using namespace drape::app;

namespace {

bool stable(const ViewSession& s) {
    return double(s.params().dt) <= stability_bound(s.sim().cloth(), s.params().air_drag).dt_max;
}

} // namespace

TEST(ViewSession, StartsStableWithCornersPinned) {
    ViewSession s(16, 1, std::nullopt);
    EXPECT_TRUE(stable(s));
    EXPECT_TRUE(s.auto_substeps());
    EXPECT_GE(s.substeps(), 10);
    // Automatic substeps cover 1/60 s per frame at this small size.
    EXPECT_GE(double(s.substeps()) * s.params().dt, view_frame_seconds * 0.999);
    ASSERT_EQ(s.pinned().size(), 2u);
    EXPECT_EQ(s.pinned()[0], grid_index(16, 0, 0));
    EXPECT_EQ(s.pinned()[1], grid_index(16, 15, 0));
    EXPECT_EQ(s.advance(), static_cast<std::size_t>(s.substeps()));
}

TEST(ViewSession, StifferSpringsAreCompensatedWithMoreSubsteps) {
    ViewSession s(16, 1, 10); // manual: 10 substeps per frame
    const double frame_time = double(s.substeps()) * s.params().dt;
    s.set_stiffness(SpringKind::structural, 16000.0f);
    EXPECT_EQ(s.fabric().stiffness[0], 16000.0f);
    EXPECT_EQ(s.sim().cloth().material[0].stiffness, 16000.0f);
    EXPECT_TRUE(stable(s));
    EXPECT_GT(s.substeps(), 10);
    // Same simulated time per frame (to one substep).
    EXPECT_NEAR(double(s.substeps()) * s.params().dt, frame_time, s.params().dt * 1.01);
    EXPECT_EQ(s.message().level, MessageLevel::warning);
    EXPECT_NE(s.message().text.find("substeps per frame 10 ->"), std::string::npos) << s.message().text;
    s.advance();
    EXPECT_TRUE(s.sim().health().finite);
}

TEST(ViewSession, ChangeNeedingTooManySubstepsIsRefused) {
    ViewSession s(16, 1, 900);
    const float k = s.fabric().stiffness[0];
    s.set_stiffness(SpringKind::structural, 25000.0f); // would need ~5x the substeps: > 1000
    EXPECT_EQ(s.fabric().stiffness[0], k);
    EXPECT_EQ(s.sim().cloth().material[0].stiffness, k);
    EXPECT_EQ(s.substeps(), 900);
    EXPECT_TRUE(stable(s));
    EXPECT_NE(s.message().text.find("refused"), std::string::npos) << s.message().text;
}

TEST(ViewSession, DragAndDampingKeepTheStepStable) {
    ViewSession s(16, 1, std::nullopt);
    s.set_air_drag(100.0f);
    EXPECT_EQ(s.params().air_drag, 100.0f);
    EXPECT_TRUE(stable(s));
    s.set_damping_ratio(1.0f);
    EXPECT_EQ(s.fabric().damping_ratio, 1.0f);
    EXPECT_TRUE(stable(s));
    s.set_stiffness(SpringKind::shear, 100.0f); // softer: dt may grow again, still stable
    EXPECT_TRUE(stable(s));
    s.advance();
    EXPECT_TRUE(s.sim().health().finite);
}

TEST(ViewSession, DtSliderCannotExceedTheBound) {
    ViewSession s(16, 1, std::nullopt);
    s.set_dt(10.0 * s.dt_bound());
    EXPECT_LE(double(s.params().dt), s.dt_bound());
    EXPECT_TRUE(stable(s));
    EXPECT_FALSE(s.auto_dt());
}

TEST(ViewSession, NodeMassRebuildKeepsMotionAndPins) {
    ViewSession s(16, 1, std::nullopt);
    s.advance();
    s.advance();
    s.toggle_pin(grid_index(16, 8, 15)); // a user pin
    const float y_before = s.sim().y()[grid_index(16, 8, 8)];
    const auto generation = s.generation();
    s.set_node_mass(0.002f); // lighter: smaller dt, more substeps (automatic)
    EXPECT_NE(s.generation(), generation);
    EXPECT_FLOAT_EQ(s.fabric().node_mass_g, 0.002f);
    EXPECT_FLOAT_EQ(s.sim().y()[grid_index(16, 8, 8)], y_before);
    EXPECT_TRUE(s.sim().is_pinned(grid_index(16, 8, 15)));
    EXPECT_TRUE(s.sim().is_pinned(grid_index(16, 0, 0)));
    EXPECT_EQ(s.pinned().size(), 3u);
    EXPECT_TRUE(stable(s));
}

TEST(ViewSession, EveryPinCanBeUnpinnedAndGrabsPin) {
    ViewSession s(16, 1, std::nullopt);
    const std::size_t corner = grid_index(16, 0, 0);
    s.toggle_pin(corner);
    EXPECT_FALSE(s.sim().is_pinned(corner)); // corners are user pins in the viewer: unpinnable
    EXPECT_EQ(s.pinned().size(), 1u);
    const std::size_t free_corner = grid_index(16, 15, 15);
    s.grab(free_corner, {0.3f, -0.2f, 0.4f});
    s.advance();
    EXPECT_FLOAT_EQ(s.sim().x()[free_corner], 0.3f);
    s.pin_grabbed();
    EXPECT_EQ(s.sim().grabbed(), SIZE_MAX);
    EXPECT_TRUE(s.sim().is_pinned(free_corner));
    s.advance();
    EXPECT_FLOAT_EQ(s.sim().z()[free_corner], 0.4f); // stays where it was dragged
}

TEST(ViewSession, ResizeRebuildsAtTheDefaultMass) {
    ViewSession s(16, 2, std::nullopt);
    s.set_size(40);
    EXPECT_EQ(s.size(), 40u);
    EXPECT_EQ(s.sim().cloth().particle_count, 1600u);
    EXPECT_NEAR(s.fabric().node_mass_g, 100.0f / 1600.0f, 1e-6f);
    EXPECT_TRUE(stable(s));
    s.set_threads(1);
    EXPECT_EQ(s.threads(), 1);
    s.advance();
    EXPECT_TRUE(s.sim().health().finite);
}

TEST(ViewSession, SceneFilesAndBuiltInScenes) {
    ViewSession s("sphere", std::nullopt, 1, std::nullopt);
    EXPECT_TRUE(s.grid_scene());
    EXPECT_FALSE(s.sim().params().colliders.empty());
    ASSERT_TRUE(s.ground_height().has_value());
    EXPECT_FLOAT_EQ(*s.ground_height(), -0.5f - 0.4f); // in the cloth's frame (origin: its centre, y 0.4)
    EXPECT_LE(s.frame_lo()[1], -0.3f); // the sphere is framed
    EXPECT_TRUE(stable(s));
    const auto scene_gen = s.scene_generation();
    s.set_scene("tshirt");
    EXPECT_NE(s.scene_generation(), scene_gen);
    EXPECT_FALSE(s.grid_scene());
    EXPECT_TRUE(s.has_seams());
    EXPECT_FALSE(s.publisher().grid_path());
    EXPECT_TRUE(stable(s));
    s.set_stiffness(SpringKind::seam, 4000.0f); // the seam slider
    EXPECT_EQ(s.fabric().stiffness[3], 4000.0f);
    EXPECT_TRUE(stable(s));
    s.advance();
    EXPECT_TRUE(s.sim().health().finite);
    s.set_scene("no_such_scene"); // refused with a message, nothing changes
    EXPECT_FALSE(s.grid_scene());
    EXPECT_NE(s.message().text.find("refused"), std::string::npos);
    EXPECT_THROW(ViewSession("tshirt", 5u, 1, std::nullopt), InvalidInput);
    EXPECT_THROW(ViewSession("nowhere", std::nullopt, 1, std::nullopt), InvalidInput);
}

TEST(ViewSession, ManualSubstepsFollowThePaceWhateverThePath) {
    // Typing 16000 into the slider applies 1, 16, 160 (clamped to 100), 1600 and 16000 in turn: the end state
    // must be that of setting 16000 at once.
    ViewSession direct(16, 1, 10), typed(16, 1, 10);
    direct.set_stiffness(SpringKind::structural, 16000.0f);
    for (float k : {1.0f, 16.0f, 160.0f, 1600.0f, 16000.0f})
        typed.set_stiffness(SpringKind::structural, k);
    EXPECT_EQ(typed.substeps(), direct.substeps());
    EXPECT_EQ(typed.params().dt, direct.params().dt);
    // Softer springs: dt grows, fewer substeps for the same simulated time per frame (at least 1).
    ViewSession soft(16, 1, 10);
    const double pace = double(soft.substeps()) * soft.params().dt;
    soft.set_stiffness(SpringKind::structural, 100.0f);
    EXPECT_LT(soft.substeps(), 10);
    EXPECT_GE(soft.substeps(), 1);
    EXPECT_NEAR(double(soft.substeps()) * soft.params().dt, pace, soft.params().dt * 1.01);
    EXPECT_TRUE(stable(soft));
}
