#include "ugv/ipc/sectors_message.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace ugv::ipc {
namespace {

SectorsMessage validMessage()
{
    SectorsMessage m;
    initSectors(m.sectors, 4, 60.0F);
    Sector& obstacle = m.sectors.sectors[0];
    obstacle.state = SectorState::Obstacle;
    obstacle.kind = ObstacleKind::Positive;
    obstacle.rangeM = 2.0F;
    obstacle.confidence = 0.5F;
    obstacle.danger = classify(obstacle.state, obstacle.rangeM, 1.5F, 5.0F);
    Sector& clear = m.sectors.sectors[1];
    clear.state = SectorState::Clear;
    clear.danger = DangerClass::Green;
    m.ground = GroundSummary{true, 12.0F, -1.0F, 0.6F};
    return m;
}

TEST(SectorsMessage, ValidMessagePasses)
{
    const SectorsMessage m = validMessage();
    EXPECT_TRUE(validate(m, sizeof(m)).has_value());
}

TEST(SectorsMessage, ShortBufferIsTooShort)
{
    const SectorsMessage m = validMessage();
    const auto result = validate(m, sizeof(m) - 1);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error(), MessageError::TooShort);
}

TEST(SectorsMessage, EachMalformedFieldHasItsError)
{
    struct Case {
        const char* what;
        void (*damage)(SectorsMessage&);
        MessageError expected;
    };
    const Case cases[] = {
        {"magic", [](SectorsMessage& m) { m.magic = 0; }, MessageError::BadMagic},
        {"version", [](SectorsMessage& m) { m.version = 99; }, MessageError::BadVersion},
        {"count 0", [](SectorsMessage& m) { m.sectors.count = 0; }, MessageError::BadCount},
        {"count too big", [](SectorsMessage& m) { m.sectors.count = kMaxSectors + 1; }, MessageError::BadCount},
        {"NaN range", [](SectorsMessage& m) { m.sectors.sectors[0].rangeM = std::numeric_limits<float>::quiet_NaN(); },
         MessageError::BadSector},
        {"obstacle at +inf",
         [](SectorsMessage& m) { m.sectors.sectors[0].rangeM = std::numeric_limits<float>::infinity(); },
         MessageError::BadSector},
        {"obstacle without kind", [](SectorsMessage& m) { m.sectors.sectors[0].kind = ObstacleKind::None; },
         MessageError::BadSector},
        {"clear with a range", [](SectorsMessage& m) { m.sectors.sectors[1].rangeM = 3.0F; }, MessageError::BadSector},
        {"unknown state enum", [](SectorsMessage& m) { m.sectors.sectors[2].state = static_cast<SectorState>(7); },
         MessageError::BadSector},
        {"confidence above 1", [](SectorsMessage& m) { m.sectors.sectors[0].confidence = 1.5F; },
         MessageError::BadSector},
        {"NaN bearing",
         [](SectorsMessage& m) { m.sectors.sectors[3].bearingMinDeg = std::numeric_limits<float>::quiet_NaN(); },
         MessageError::BadSector},
        {"unknown sector marked red", [](SectorsMessage& m) { m.sectors.sectors[2].danger = DangerClass::Red; },
         MessageError::BadSector},
        {"NaN ground pitch", [](SectorsMessage& m) { m.ground.pitchDeg = std::numeric_limits<float>::quiet_NaN(); },
         MessageError::BadGround},
        {"ground roll beyond 90 deg", [](SectorsMessage& m) { m.ground.rollDeg = 120.0F; }, MessageError::BadGround},
        {"camera below the ground", [](SectorsMessage& m) { m.ground.cameraHeightM = -0.5F; }, MessageError::BadGround},
        {"infinite camera height",
         [](SectorsMessage& m) { m.ground.cameraHeightM = std::numeric_limits<float>::infinity(); },
         MessageError::BadGround},
        {"camera state", [](SectorsMessage& m) { m.health.camera = static_cast<CameraState>(9); },
         MessageError::BadHealth},
    };
    for (const Case& c : cases) {
        SectorsMessage m = validMessage();
        c.damage(m);
        const auto result = validate(m, sizeof(m));
        ASSERT_FALSE(result.has_value()) << c.what;
        EXPECT_EQ(result.error(), c.expected) << c.what << ": " << toString(result.error());
    }
}

TEST(SectorsMessage, EveryErrorHasText)
{
    for (int e = 0; e <= static_cast<int>(MessageError::BadHealth); ++e) {
        EXPECT_STRNE(toString(static_cast<MessageError>(e)), "unknown message error");
    }
}

} // namespace
} // namespace ugv::ipc
