// The JSON helpers of the sectors and the tools' reports: numbers (null when not finite), strings (escaped), and one
// sector's line.

#include "ugv/platform/sectors_json.hpp"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

namespace {

TEST(SectorsJson, ANumberThatIsNotFiniteIsNull)
{
    EXPECT_EQ(ugv::jsonNumber(1.5), "1.5");
    EXPECT_EQ(ugv::jsonNumber(-0.25), "-0.25");
    EXPECT_EQ(ugv::jsonNumber(std::numeric_limits<double>::infinity()), "null");
    EXPECT_EQ(ugv::jsonNumber(std::nan("")), "null");
}

TEST(SectorsJson, AStringIsQuotedWithItsSpecialCharactersEscaped)
{
    EXPECT_EQ(ugv::jsonString("Motorcycle (MiddEval3 trainingQ)"), "\"Motorcycle (MiddEval3 trainingQ)\"");
    EXPECT_EQ(ugv::jsonString("a\"b\\c"), "\"a\\\"b\\\\c\"");
    EXPECT_EQ(ugv::jsonString("line\nnext\ttab\r"), "\"line\\nnext\\ttab\\r\"");
    EXPECT_EQ(ugv::jsonString(std::string("bell\x07", 5)), "\"bell\\u0007\"");
    EXPECT_EQ(ugv::jsonString(""), "\"\"");
}

TEST(SectorsJson, EachSectorIsOneLineWithAnInfiniteRangeAsNull)
{
    ugv::ObstacleSectors sectors;
    ugv::initSectors(sectors, 2, 60.0F);
    sectors.sectors[0].state = ugv::SectorState::Obstacle;
    sectors.sectors[0].kind = ugv::ObstacleKind::Negative;
    sectors.sectors[0].rangeM = 2.5F;
    const std::string json = ugv::sectorsJsonArray(sectors, 2);
    EXPECT_NE(json.find("\"range_m\": 2.5"), std::string::npos) << json;
    EXPECT_NE(json.find("\"kind\": \"negative\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"state\": \"obstacle\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"range_m\": null"), std::string::npos) << json; // the second sector: nothing measured
}

} // namespace
