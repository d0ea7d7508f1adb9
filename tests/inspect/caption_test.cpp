// Titles, legends and scale bars (caption.hpp, captioned.hpp) and the font under them:
// text draws pixels of its colour inside its cells and nowhere else, the bands hold
// text where it should be and leave the picture untouched, a legend swatch shows its
// colour, the scale bar is as long as the map scale says, and pyramid faces carry
// their labels.

#include "dsoc/inspect/caption.hpp"
#include "dsoc/inspect/captioned.hpp"
#include "dsoc/inspect/font.hpp"
#include "dsoc/inspect/plan_legend.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dsoc::inspect {
namespace {

constexpr Rgb kBackground = CaptionStyle{}.background;
constexpr Rgb kText = CaptionStyle{}.text;

/// Pixels equal to `c` in the rectangle [x0, x1) x [y0, y1).
int count(const Image& image, Rgb c, int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = std::max(y0, 0); y < std::min(y1, image.height()); ++y) {
        for (int x = std::max(x0, 0); x < std::min(x1, image.width()); ++x) {
            n += image.at(x, y) == c ? 1 : 0;
        }
    }
    return n;
}

/// A picture no caption colour appears in.
Image picture(int width, int height) {
    return Image(width, height, Rgb{1, 2, 3});
}

TEST(Font, TextDrawsInsideItsCellsOnly) {
    Image image(100, 40, kBackground);
    const int end = draw_text(image, 10, 5, "Ag", {kText});
    EXPECT_EQ(end, 10 + 2 * kGlyphWidth);
    EXPECT_EQ(text_width("Ag"), 2 * kGlyphWidth);
    EXPECT_GT(count(image, kText, 10, 5, 10 + kGlyphWidth, 5 + kGlyphHeight), 5); // 'A'
    EXPECT_GT(count(image, kText, 16, 5, 16 + kGlyphWidth, 5 + kGlyphHeight), 5); // 'g'
    EXPECT_EQ(count(image, kText, 0, 0, 100, 40),
              count(image, kText, 10, 5, 10 + 2 * kGlyphWidth, 5 + kGlyphHeight));
    // A space draws nothing; a byte outside ASCII draws as '?'.
    Image blank(20, 20, kBackground);
    draw_text(blank, 0, 0, " ", {kText});
    EXPECT_EQ(count(blank, kText, 0, 0, 20, 20), 0);
    Image a(20, 20, kBackground), b(20, 20, kBackground);
    draw_text(a, 0, 0, "\x80", {kText});
    draw_text(b, 0, 0, "?", {kText});
    EXPECT_EQ(a.pixels(), b.pixels());
}

TEST(Font, BoldAndScaledDiffer) {
    Image regular(40, 40, kBackground), bold(40, 40, kBackground), big(40, 40, kBackground);
    draw_text(regular, 0, 0, "H", {kText});
    draw_text(bold, 0, 0, "H", {kText, FontWeight::bold});
    draw_text(big, 0, 0, "H", {kText, FontWeight::regular, 2});
    const int n = count(regular, kText, 0, 0, 40, 40);
    EXPECT_GT(count(bold, kText, 0, 0, 40, 40), n);
    EXPECT_EQ(count(big, kText, 0, 0, 40, 40), 4 * n);
    EXPECT_EQ(text_height(2), 2 * kGlyphHeight);
}

TEST(Caption, TitleBandHoldsTheTextAndThePictureIsUnchanged) {
    const Image p = picture(300, 50);
    const Image titled = with_title(p, {"oa_dm4 | client 1", "second line"});
    const int band = titled.height() - p.height();
    ASSERT_GE(band, 2 * kGlyphHeight);
    EXPECT_EQ(Image::cropped(titled, 0, band, p.width(), p.height()).pixels(), p.pixels());
    // Text where the lines are, the band's background elsewhere (right of the text).
    const int pad = CaptionStyle{}.padding;
    EXPECT_GT(count(titled, kText, pad, pad, pad + text_width("oa_dm4"), pad + kGlyphHeight), 10);
    EXPECT_GT(count(titled, kText, pad, pad + kGlyphHeight, 150, pad + 2 * kGlyphHeight), 10);
    EXPECT_EQ(count(titled, kText, 200, 0, 300, band), 0);
}

TEST(Caption, LongTitlesWrapToThePictureWidth) {
    const Image p = picture(120, 10);
    const Image one = with_title(p, {"short"});
    const Image wrapped = with_title(p, {"a title far longer than twenty characters"});
    EXPECT_GE(wrapped.height() - one.height(), 2 * kGlyphHeight);
}

TEST(Caption, ScaleBarUnitsAreOneTwoOrFiveTimesAPowerOfTen) {
    EXPECT_FLOAT_EQ(scale_bar_units(2.0f, 160), 200.0f);   // at most 320 units
    EXPECT_FLOAT_EQ(scale_bar_units(4.0f, 160), 500.0f);   // at most 640
    EXPECT_FLOAT_EQ(scale_bar_units(1.0f, 160), 100.0f);   // at most 160
    EXPECT_FLOAT_EQ(scale_bar_units(10.0f, 100), 1000.0f); // exactly 1000
    EXPECT_FLOAT_EQ(scale_bar_units(0.01f, 160), 1.0f);    // at most 1.6
    EXPECT_FLOAT_EQ(scale_bar_units(0.001f, 160), 0.1f);
}

/// The longest horizontal run of `c` in rows [y0, y1). [Units: pixels]
int longest_run(const Image& image, Rgb c, int y0, int y1) {
    int best = 0;
    for (int y = y0; y < y1; ++y) {
        int run = 0;
        for (int x = 0; x < image.width(); ++x) {
            run = image.at(x, y) == c ? run + 1 : 0;
            best = std::max(best, run);
        }
    }
    return best;
}

TEST(Caption, ScaleBarLengthMatchesTheMapScale) {
    for (const float upp : {1.0f, 2.0f, 3.0f, 4.0f}) {
        const Image p = picture(400, 30);
        const Image out = with_legend(p, {}, ScaleBar{upp});
        const float units = scale_bar_units(upp, ScaleBar{}.max_pixels);
        // No legend text: the bar is the longest run of text colour under the picture.
        EXPECT_EQ(longest_run(out, kText, p.height(), out.height()),
                  static_cast<int>(std::lround(units / upp)))
            << upp << " units per pixel";
    }
}

TEST(Caption, LegendShowsEachSwatchAndItsLabel) {
    const Rgb red{200, 10, 10}, blue{10, 10, 200}, grey{90, 90, 90};
    const std::vector<LegendEntry> entries = {
        {LegendEntry::Swatch::fill, red, {}, "red thing"},
        {LegendEntry::Swatch::outline, blue, {}, "blue box"},
        {LegendEntry::Swatch::gradient, Rgb{0, 0, 0}, grey, "shade"}};
    const Image p = picture(600, 40);
    const Image out = with_legend(p, entries);
    ASSERT_GT(out.height(), p.height());
    EXPECT_EQ(Image::cropped(out, 0, 0, p.width(), p.height()).pixels(), p.pixels());
    const int side = CaptionStyle{}.swatch;
    EXPECT_EQ(count(out, red, 0, p.height(), out.width(), out.height()), side * side);
    EXPECT_EQ(count(out, blue, 0, p.height(), out.width(), out.height()), 4 * (side - 1));
    EXPECT_GT(count(out, grey, 0, p.height(), out.width(), out.height()), 0);
    EXPECT_GT(count(out, kText, 0, p.height(), out.width(), out.height()), 50);
}

TEST(Caption, NarrowLegendsWrapTheirLabels) {
    const std::vector<LegendEntry> entries = {
        {LegendEntry::Swatch::fill, Rgb{200, 10, 10}, {}, "a label much wider than the picture"}};
    const Image wide = with_legend(picture(400, 10), entries);
    const Image narrow = with_legend(picture(100, 10), entries);
    EXPECT_GE(narrow.height() - wide.height(), 2 * kGlyphHeight);
    // Text on the label's second line too.
    const int pad = CaptionStyle{}.padding;
    const int second = 10 + pad + std::max(kGlyphHeight, CaptionStyle{}.swatch) + 3;
    EXPECT_GT(count(narrow, kText, 0, second, 100, second + kGlyphHeight), 5);
}

TEST(Caption, ColumnLabelsAreCentredAboveTheirCells) {
    const Image strip = picture(3 * 60 + 4 * 5, 60);
    const Image out = with_column_labels(strip, {"a", "b", "c"}, 5, 60, 5);
    const int band = out.height() - strip.height();
    ASSERT_GE(band, kGlyphHeight);
    for (int i = 0; i < 3; ++i) {
        const int centre = 5 + i * 65 + 30;
        EXPECT_GT(count(out, kText, centre - 6, 0, centre + 6, band), 3) << "cell " << i;
    }
}

TEST(PlanLegend, LiveListsEveryStateWithItsCountTraceOnlyItsFive) {
    ClientView view;
    view.entities = {{1, {}, EntityState::replicated_visible, {}},
                     {2, {}, EntityState::replicated_visible, {}},
                     {3, {}, EntityState::hidden_expired, {}}};
    const auto live = plan_legend(view);
    const auto has = [](const std::vector<LegendEntry>& l, Rgb c, const std::string& text) {
        for (const LegendEntry& e : l) {
            if (e.colour == c && e.label.find(text) != std::string::npos) {
                return true;
            }
        }
        return false;
    };
    EXPECT_TRUE(has(live, kPalette.replicated_visible, "(2)"));
    EXPECT_TRUE(has(live, kPalette.hidden_expired, "(1)"));
    EXPECT_TRUE(has(live, kPalette.replicated_held, "(0)"));
    EXPECT_TRUE(has(live, kPalette.replicated_heard, "heard"));
    EXPECT_TRUE(has(live, kPalette.replicated_rule, "teammate"));
    EXPECT_TRUE(has(live, kPalette.tbv_outline, "TBV"));
    EXPECT_TRUE(has(live, kPalette.eye_region, "latency"));
    EXPECT_FALSE(has(live, kPalette.not_replicated, ""));

    const auto trace = plan_legend(view, {.from_trace = true, .counts = false});
    EXPECT_TRUE(has(trace, kPalette.not_replicated, "not sent"));
    EXPECT_TRUE(has(trace, kPalette.replicated_heard, "heard"));
    EXPECT_TRUE(has(trace, kPalette.replicated_rule, "teammate"));
    EXPECT_FALSE(has(trace, kPalette.hidden_tbv, ""));
    EXPECT_FALSE(has(trace, kPalette.eye_region, ""));
    EXPECT_FALSE(has(trace, kPalette.replicated_visible, "("));
}

TEST(Captioned, PlanHasTitleLegendAndScaleAroundIt) {
    const Image plan = picture(500, 300);
    ClientView view;
    view.client = 3;
    view.tick = 60;
    view.entities = {{1, {}, EntityState::hidden_tbv, {}}};
    PlanStyle style;
    style.units_per_pixel = 2.0f;
    const RunInfo run{"oa_dm4", "dsoc", 30, false, "live: 1 bot"};
    EXPECT_EQ(headline(run, view), "oa_dm4 | client 3 | tick 60 (2.0 s) | policy dsoc");
    const Image out = captioned_plan(plan, run, view, style);
    const int above = with_title(plan, {headline(run, view), "x"}).height() - plan.height();
    ASSERT_GT(out.height(), plan.height() + above);
    EXPECT_EQ(Image::cropped(out, 0, above, plan.width(), plan.height()).pixels(), plan.pixels());
    EXPECT_GT(count(out, kText, 0, 0, out.width(), above), 100);
    const int below = above + plan.height();
    EXPECT_GT(count(out, kPalette.hidden_tbv, 0, below, out.width(), out.height()), 0);
    EXPECT_GT(count(out, kPalette.replicated_visible, 0, below, out.width(), out.height()), 0);
    EXPECT_EQ(longest_run(out, kText, below, out.height()),
              static_cast<int>(scale_bar_units(2.0f, ScaleBar{}.max_pixels) / 2.0f));
}

TEST(Captioned, FramesKeepOneSizeWhateverTheirTick) {
    const RunInfo run{"oa_dm4", "dsoc", 30, false, "live"};
    ClientView first, later;
    first.tick = 9;
    later.tick = 123456;
    const Image a = labeled_frame(picture(200, 200), run, first);
    const Image b = labeled_frame(picture(200, 200), run, later);
    EXPECT_EQ(a.width(), b.width());
    EXPECT_EQ(a.height(), b.height());
    EXPECT_NE(a.pixels(), b.pixels());
    EXPECT_GT(count(a, kText, 0, 0, 120, 20), 10); // "tick 9 (0.3 s)" in the corner
}

} // namespace
} // namespace dsoc::inspect
