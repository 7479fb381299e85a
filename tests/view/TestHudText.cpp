// The HUD's text (viewer/src/Hud.h formatHud): counts get thousands separators, whatever their
// number of digits, and every field the issue names is on it.

#include "Hud.h"

#include <gtest/gtest.h>

namespace ff::viewer {
namespace {

TEST(HudTextTest, CountsGetThousandsSeparators) {
    HudInfo info;
    info.trianglesDrawn = 1'234'567;
    info.cubesDrawn = 999;
    info.debt = 1'000;
    const std::string text = formatHud(info);
    EXPECT_NE(text.find("triangles 1,234,567 "), std::string::npos) << text;
    EXPECT_NE(text.find("cubes 999 "), std::string::npos) << text;
    EXPECT_NE(text.find("deferred 1,000\n"), std::string::npos) << text;

    info.trianglesDrawn = 0;
    info.cubesDrawn = 100'000;
    info.debt = 12'345'678'901ull;
    const std::string other = formatHud(info);
    EXPECT_NE(other.find("triangles 0 "), std::string::npos) << other;
    EXPECT_NE(other.find("cubes 100,000 "), std::string::npos) << other;
    EXPECT_NE(other.find("deferred 12,345,678,901\n"), std::string::npos) << other;
}

TEST(HudTextTest, ShowsRateMethodAndSize) {
    HudInfo info;
    info.frameMs = 20.0;
    info.epsilonPixels = 2.0f;
    info.method = runtime::Method::Full;
    info.width = 640;
    info.height = 480;
    const std::string text = formatHud(info);
    EXPECT_NE(text.find("50.0 fps"), std::string::npos) << text;
    EXPECT_NE(text.find("method full"), std::string::npos) << text;
    EXPECT_NE(text.find("eps 2 px"), std::string::npos) << text;
    EXPECT_NE(text.find("640x480"), std::string::npos) << text;
}

} // namespace
} // namespace ff::viewer
