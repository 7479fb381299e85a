#include <ff/runtime/ImageMetrics.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

// Known answers are derived by hand in the comments; the tests recompute them from the formulas
// (not from src/) so a wrong window, constant or transfer function fails them.

namespace ff::runtime {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Image makeImage(int width, int height, std::uint8_t grey, std::uint8_t alpha = 255) {
    Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(static_cast<std::size_t>(width * height * 4));
    for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
        image.rgba[i] = image.rgba[i + 1] = image.rgba[i + 2] = grey;
        image.rgba[i + 3] = alpha;
    }
    return image;
}

void setGrey(Image& image, int x, int y, std::uint8_t grey) {
    std::uint8_t* px = image.pixel(x, y);
    px[0] = px[1] = px[2] = grey;
}

/** A deterministic image with structure in every channel (an LCG; values are irrelevant). */
Image makeNoise(int width, int height) {
    Image image = makeImage(width, height, 0);
    std::uint32_t state = 12345u;
    for (std::uint8_t& byte : image.rgba) {
        state = state * 1664525u + 1013904223u;
        byte = static_cast<std::uint8_t>(state >> 24);
    }
    return image;
}

/** sRGB code -> linear, straight from IEC 61966-2-1. */
double srgbToLinear(int code) {
    const double c = code / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

/** Normalised weight of offset d (-5..5) in the 1D Gaussian, sigma 1.5. */
double gaussianWeight(int d) {
    double sum = 0.0;
    for (int i = -5; i <= 5; ++i)
        sum += std::exp(-i * i / (2.0 * 1.5 * 1.5));
    return std::exp(-d * d / (2.0 * 1.5 * 1.5)) / sum;
}

constexpr double kC1 = (0.01 * 255) * (0.01 * 255); // 6.5025
constexpr double kC2 = (0.03 * 255) * (0.03 * 255); // 58.5225

// ---------------------------------------------------------------------------------------------
// Colour error

TEST(ImageMetricsTest, IdenticalImagesHaveZeroErrorAndInfinitePsnr) {
    const Image image = makeNoise(16, 16);
    const auto error = colorError(image, image);
    ASSERT_TRUE(error.isOk()) << error.status().toString();
    EXPECT_EQ(error->rmseSrgb, 0.0);
    EXPECT_EQ(error->rmseLinear, 0.0);
    EXPECT_EQ(error->psnrSrgb, kInf);
    EXPECT_EQ(error->psnrLinear, kInf);
}

TEST(ImageMetricsTest, OneChannelOfOnePixelGivesExactRmse) {
    // 4x4 image, green of pixel (2,1) changed by 30: one squared error of 900 among
    // 16 pixels * 3 channels = 48 samples -> RMSE = sqrt(900 / 48) = sqrt(18.75) = 4.3301270189.
    // PSNR = 20 log10(255 / 4.3301270189) = 35.4007908880 dB.
    const Image reference = makeImage(4, 4, 100);
    Image approximation = reference;
    approximation.pixel(2, 1)[1] = 130;
    const auto error = colorError(approximation, reference);
    ASSERT_TRUE(error.isOk()) << error.status().toString();
    EXPECT_DOUBLE_EQ(error->rmseSrgb, std::sqrt(900.0 / 48.0));
    EXPECT_NEAR(error->rmseSrgb, 4.3301270189, 1e-9);
    EXPECT_NEAR(error->psnrSrgb, 35.4007908880, 1e-9);
    // Linear: (lin(130) - lin(100))^2 / 48 under the square root.
    const double dl = srgbToLinear(130) - srgbToLinear(100);
    EXPECT_NEAR(error->rmseLinear, std::abs(dl) / std::sqrt(48.0), 1e-7);
}

TEST(ImageMetricsTest, LinearRmseUsesTheSrgbTransferFunction) {
    // Every channel of every pixel: 128 vs 64.
    //   sRGB:   RMSE = 64, PSNR = 20 log10(255/64) = 12.0072041290 dB.
    //   lin(128) = ((128/255 + 0.055) / 1.055)^2.4 = (0.5541322 / 1.055)^2.4 = 0.2158605001
    //   lin(64)  = ((64/255  + 0.055) / 1.055)^2.4 = (0.3059804 / 1.055)^2.4 = 0.0512694584
    //   linear RMSE = 0.2158605001 - 0.0512694584 = 0.1645910417,
    //   PSNR = -20 log10(0.1645910417) = 15.6718761 dB.
    // A plain gamma 2.2 would give 0.2195 - 0.0487 = 0.1708 instead, so this tells them apart.
    const auto error = colorError(makeImage(3, 5, 128), makeImage(3, 5, 64));
    ASSERT_TRUE(error.isOk()) << error.status().toString();
    EXPECT_EQ(error->rmseSrgb, 64.0);
    EXPECT_NEAR(error->psnrSrgb, 12.0072041290, 1e-9);
    EXPECT_NEAR(error->rmseLinear, 0.1645910417, 1e-7);
    EXPECT_NEAR(error->psnrLinear, 15.6718761, 1e-5);
}

TEST(ImageMetricsTest, ColorErrorIgnoresAlpha) {
    // Colour is already composited; coverage has its own metric.
    const auto error = colorError(makeImage(2, 2, 50, 0), makeImage(2, 2, 50, 255));
    ASSERT_TRUE(error.isOk());
    EXPECT_EQ(error->rmseSrgb, 0.0);
}

TEST(ImageMetricsTest, MismatchedOrMalformedImagesAreInvalidArguments) {
    const auto mismatch = colorError(makeImage(4, 4, 0), makeImage(4, 5, 0));
    ASSERT_FALSE(mismatch.isOk());
    EXPECT_EQ(mismatch.status().code(), ErrorCode::InvalidArgument);
    EXPECT_NE(mismatch.status().message().find("4x5"), std::string::npos);

    Image truncated = makeImage(4, 4, 0);
    truncated.rgba.resize(60); // as if read from a short file
    EXPECT_EQ(
            colorError(truncated, makeImage(4, 4, 0)).status().code(), ErrorCode::InvalidArgument);

    const Image empty;
    EXPECT_EQ(colorError(empty, empty).status().code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(ssim(empty, empty).status().code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(coverageError(empty, empty).status().code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(
            ssim(makeImage(16, 16, 0), makeImage(16, 15, 0)).status().code(),
            ErrorCode::InvalidArgument);
    EXPECT_EQ(
            coverageError(makeImage(3, 3, 0), makeImage(2, 3, 0)).status().code(),
            ErrorCode::InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// SSIM

TEST(ImageMetricsTest, SsimOfIdenticalImagesIsExactlyOne) {
    const Image image = makeNoise(23, 17);
    const auto value = ssim(image, image);
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_EQ(*value, 1.0);
}

TEST(ImageMetricsTest, SsimOfConstantImagesIsTheLuminanceTerm) {
    // Zero variance everywhere: the contrast-structure term is (0 + C2) / (0 + C2) = 1 and
    // SSIM = (2 mu1 mu2 + C1) / (mu1^2 + mu2^2 + C1) with mu1 = 100, mu2 = 150 (grey luma = code):
    //   (30000 + 6.5025) / (10000 + 22500 + 6.5025) = 30006.5025 / 32506.5025 = 0.9230923105.
    const auto value = ssim(makeImage(16, 16, 100), makeImage(16, 16, 150));
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, (2.0 * 100 * 150 + kC1) / (100.0 * 100 + 150.0 * 150 + kC1), 1e-9);
    EXPECT_NEAR(*value, 0.9230923105, 1e-9);
}

TEST(ImageMetricsTest, SsimOfCheckerboardAgainstItsNegativeMatchesClosedForm) {
    // x = black/white checkerboard, y = 255 - x. With the 1D weights split into E (even
    // offsets -4..4) and O (odd offsets +-1, +-3, +-5), cells of the centre's parity weigh
    // p = E^2 + O^2 and the others q = 2EO (p + q = 1). Centre on a black cell of x:
    //   mu_x = 255 q, var_x = 255^2 q - (255 q)^2 = 255^2 pq
    //   mu_y = 255 p, var_y = 255^2 pq, E[xy] = 0 so cov = -255^2 pq
    //   with v = 255^2 pq:
    //   SSIM = (2v + C1)(-2v + C2) / ((255^2 (p^2 + q^2) + C1)(2v + C2))
    // The same with p, q swapped on white centres, so every window, and the mean, equal it.
    // E = 0.49993062, O = 0.50006938 -> p = 0.50000001, q = 0.49999999 -> SSIM = -0.99640647.
    Image x = makeImage(16, 16, 0);
    Image y = makeImage(16, 16, 255);
    for (int row = 0; row < 16; ++row) {
        for (int col = 0; col < 16; ++col) {
            if ((row + col) % 2 == 1) {
                setGrey(x, col, row, 255);
                setGrey(y, col, row, 0);
            }
        }
    }
    double even = 0.0;
    for (int d = -4; d <= 4; d += 2)
        even += gaussianWeight(d);
    const double odd = 1.0 - even;
    const double p = even * even + odd * odd;
    const double q = 2.0 * even * odd;
    const double v = 255.0 * 255.0 * p * q;
    const double expected = (2 * v + kC1) * (-2 * v + kC2) /
                            ((255.0 * 255.0 * (p * p + q * q) + kC1) * (2 * v + kC2));

    const auto value = ssim(x, y);
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, expected, 1e-9);
    EXPECT_NEAR(*value, -0.99640647, 1e-8);
}

TEST(ImageMetricsTest, SsimOfConstantOffsetIsTheMeanLuminanceTerm) {
    // x = checkerboard of 50/150, y = x + 40: var_y = var_x = cov, so the contrast-structure
    // term is 1 and each window is l(m) = (2 m (m + 40) + C1) / (m^2 + (m + 40)^2 + C1), with
    // m = 50p + 150q on centres of value 50 and 150p + 50q on centres of 150 (p, q as above).
    // 16x16 -> 6x6 window centres (5..10), 18 of each parity, so the mean is the average.
    Image x = makeImage(16, 16, 50);
    Image y = makeImage(16, 16, 90);
    for (int row = 0; row < 16; ++row) {
        for (int col = 0; col < 16; ++col) {
            if ((row + col) % 2 == 1) {
                setGrey(x, col, row, 150);
                setGrey(y, col, row, 190);
            }
        }
    }
    double even = 0.0;
    for (int d = -4; d <= 4; d += 2)
        even += gaussianWeight(d);
    const double odd = 1.0 - even;
    const double p = even * even + odd * odd;
    const double q = 2.0 * even * odd;
    auto luminanceTerm = [](double m) {
        return (2 * m * (m + 40) + kC1) / (m * m + (m + 40) * (m + 40) + kC1);
    };
    const double expected = (luminanceTerm(50 * p + 150 * q) + luminanceTerm(150 * p + 50 * q)) / 2;

    const auto value = ssim(x, y);
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, expected, 1e-9);
    EXPECT_NEAR(*value, 0.9459578179, 1e-9); // both l(m) are about 0.945957818 (m ~ 100)
}

TEST(ImageMetricsTest, SsimOfCentredImpulseWeighsItWithTheCentreGaussianWeight) {
    // 11x11 has exactly one window. x = black with one white pixel at the centre, y = black.
    // Centre weight w = g(0)^2 = (1 / sum_{d=-5..5} exp(-d^2 / 4.5))^2 = 0.2660117^2 = 0.0707622
    // (the truncated window's sum is 3.759233, not the untruncated sqrt(2 pi) 1.5 = 3.759942).
    //   mu_x = 255 w, var_x = 255^2 w (1 - w), mu_y = var_y = cov = 0
    //   SSIM = C1 C2 / ((255^2 w^2 + C1)(255^2 w (1 - w) + C2))
    //        = 380.543 / ((325.599 + 6.5025)(4275.715 + 58.5225)) = 0.000264374
    // Sensitive to sigma and normalisation: a box window (w = 1/121) gives 0.0588.
    Image x = makeImage(11, 11, 0);
    setGrey(x, 5, 5, 255);
    const double w = gaussianWeight(0) * gaussianWeight(0);
    const double expected =
            kC1 * kC2 / ((255.0 * 255.0 * w * w + kC1) * (255.0 * 255.0 * w * (1 - w) + kC2));
    const auto value = ssim(x, makeImage(11, 11, 0));
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, expected, 1e-12);
    EXPECT_NEAR(*value, 0.000264374, 1e-9);
    EXPECT_NEAR(gaussianWeight(0), 0.2660117, 1e-7);
}

TEST(ImageMetricsTest, SsimAveragesOnlyValidWindowPositions) {
    // 12x11 -> two windows (left edge at column 0 and 1). A white pixel at (11, 5) lies only in
    // the second window, at its right-middle, weight w = g(5) g(0); the first window sees two
    // identical black images, SSIM 1. Mean = (1 + s) / 2 with
    //   s = C1 C2 / ((255^2 w^2 + C1)(255^2 w (1 - w) + C2)).
    // Padding the border instead would add windows and change the mean.
    Image x = makeImage(12, 11, 0);
    setGrey(x, 11, 5, 255);
    const double w = gaussianWeight(5) * gaussianWeight(0);
    const double s =
            kC1 * kC2 / ((255.0 * 255.0 * w * w + kC1) * (255.0 * 255.0 * w * (1 - w) + kC2));
    const auto value = ssim(x, makeImage(12, 11, 0));
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, (1.0 + s) / 2.0, 1e-12);
    EXPECT_LT(*value, 1.0);
}

TEST(ImageMetricsTest, SsimUsesRec709LumaOfCodedValues) {
    // Red 200 vs green 200 differ in luma: 0.2126 * 200 = 42.52 vs 0.7152 * 200 = 143.04;
    // constant images, so SSIM = (2 * 42.52 * 143.04 + C1) / (42.52^2 + 143.04^2 + C1).
    Image red = makeImage(11, 11, 0);
    Image green = makeImage(11, 11, 0);
    for (int row = 0; row < 11; ++row) {
        for (int col = 0; col < 11; ++col) {
            red.pixel(col, row)[0] = 200;
            green.pixel(col, row)[1] = 200;
        }
    }
    const double a = 42.52;
    const double b = 143.04;
    const auto value = ssim(red, green);
    ASSERT_TRUE(value.isOk()) << value.status().toString();
    EXPECT_NEAR(*value, (2 * a * b + kC1) / (a * a + b * b + kC1), 1e-9);
}

TEST(ImageMetricsTest, SsimRejectsImagesSmallerThanTheWindow) {
    const auto value = ssim(makeImage(10, 20, 0), makeImage(10, 20, 0));
    ASSERT_FALSE(value.isOk());
    EXPECT_EQ(value.status().code(), ErrorCode::InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// Coverage

TEST(ImageMetricsTest, CoverageCountsHolesAndOverCoverage) {
    // 3x2, alpha codes; covered means alpha >= 0.5 * 255 = 127.5, i.e. code >= 128.
    //   pixel          0    1    2    3    4    5
    //   approximation  0  127  128    0  200    0
    //   reference    255  128  127    0  255    0
    //   -> holes at 0 and 1 (approx background, reference covered), over-coverage at 2,
    //      agreement at 3, 4, 5: holes 2/6, over-coverage 1/6.
    const std::uint8_t approxAlpha[] = {0, 127, 128, 0, 200, 0};
    const std::uint8_t refAlpha[] = {255, 128, 127, 0, 255, 0};
    Image approximation = makeImage(3, 2, 0);
    Image reference = makeImage(3, 2, 0);
    for (std::size_t i = 0; i < 6; ++i) {
        approximation.rgba[i * 4 + 3] = approxAlpha[i];
        reference.rgba[i * 4 + 3] = refAlpha[i];
    }
    const auto error = coverageError(approximation, reference);
    ASSERT_TRUE(error.isOk()) << error.status().toString();
    EXPECT_EQ(error->holes, 2u);
    EXPECT_EQ(error->overCoverage, 1u);
    EXPECT_EQ(error->pixelCount, 6u);
    EXPECT_DOUBLE_EQ(error->holeFraction, 2.0 / 6.0);
    EXPECT_DOUBLE_EQ(error->overCoverageFraction, 1.0 / 6.0);

    // Threshold 0.9 -> cut 229.5: no approximation pixel is covered (max 200); reference
    // pixels 0 and 4 (255) are -> holes 2 (pixels 0, 4), over-coverage 0.
    const auto strict = coverageError(approximation, reference, 0.9f);
    ASSERT_TRUE(strict.isOk());
    EXPECT_EQ(strict->holes, 2u);
    EXPECT_EQ(strict->overCoverage, 0u);

    // Swapping the roles swaps the two counts.
    const auto swapped = coverageError(reference, approximation);
    ASSERT_TRUE(swapped.isOk());
    EXPECT_EQ(swapped->holes, 1u);
    EXPECT_EQ(swapped->overCoverage, 2u);
}

TEST(ImageMetricsTest, CoverageRejectsThresholdOutsideUnitRange) {
    const Image image = makeImage(2, 2, 0);
    EXPECT_EQ(coverageError(image, image, 1.5f).status().code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(coverageError(image, image, -0.1f).status().code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(
            coverageError(image, image, std::numeric_limits<float>::quiet_NaN()).status().code(),
            ErrorCode::InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// Temporal instability

TEST(ImageMetricsTest, FlickerAgainstStaticReferenceGivesHandComputedMean) {
    // 2x2 frames, reference static grey 128. Approximation: pixel (0,0) goes white, black,
    // grey 128; the other three pixels stay 128. Grey luminance = lin(code) (coefficients sum
    // to 1).
    //   pair 0-1: |lin(0) - lin(255)| = 1 at one pixel of 4          -> 0.25
    //   pair 1-2: |lin(128) - lin(0)| = 0.2158605001 at one pixel of 4 -> 0.0539651250
    //   mean = (0.25 + 0.0539651250) / 2 = 0.1519825625, max = 0.25
    const Image grey = makeImage(2, 2, 128);
    std::vector<Image> approximation(3, grey);
    setGrey(approximation[0], 0, 0, 255);
    setGrey(approximation[1], 0, 0, 0);
    const std::vector<Image> reference(3, grey);

    const auto result = temporalInstability(approximation, reference);
    ASSERT_TRUE(result.isOk()) << result.status().toString();
    EXPECT_EQ(result->framePairs, 2u);
    EXPECT_NEAR(result->mean, 0.1519825625, 1e-7);
    EXPECT_NEAR(result->maxFrame, 0.25, 1e-7);

    // The pair function plus the accumulator reproduce the sequence result.
    TemporalInstabilityAccumulator accumulator;
    for (std::size_t t = 1; t < 3; ++t) {
        const auto pair = temporalInstability(
                approximation[t - 1], approximation[t], reference[t - 1], reference[t]);
        ASSERT_TRUE(pair.isOk());
        accumulator.add(*pair);
    }
    EXPECT_NEAR(
            *temporalInstability(approximation[1], approximation[2], grey, grey),
            0.0539651250,
            1e-7);
    EXPECT_EQ(accumulator.result().mean, result->mean);
    EXPECT_EQ(accumulator.result().maxFrame, result->maxFrame);
    EXPECT_EQ(accumulator.result().framePairs, 2u);
}

TEST(ImageMetricsTest, ApproximationChangingLikeTheReferenceIsStable) {
    // Reference pixel (1,0) goes black -> white -> black (camera motion). The approximation
    // shows the same change at (1,0) but inverted (white -> black -> white): |dA| = |dR| = 1, so
    // the excess is 0. The approximation is wrong but not unstable; other metrics catch that.
    std::vector<Image> reference(3, makeImage(2, 2, 60));
    std::vector<Image> approximation(3, makeImage(2, 2, 90));
    const std::uint8_t refCodes[] = {0, 255, 0};
    const std::uint8_t approxCodes[] = {255, 0, 255};
    for (std::size_t t = 0; t < 3; ++t) {
        setGrey(reference[t], 1, 0, refCodes[t]);
        setGrey(approximation[t], 1, 0, approxCodes[t]);
    }
    const auto inverted = temporalInstability(approximation, reference);
    ASSERT_TRUE(inverted.isOk()) << inverted.status().toString();
    EXPECT_NEAR(inverted->mean, 0.0, 1e-12);
    EXPECT_NEAR(inverted->maxFrame, 0.0, 1e-12);

    const auto same = temporalInstability(reference, reference);
    ASSERT_TRUE(same.isOk());
    EXPECT_EQ(same->mean, 0.0);

    // A static approximation against a moving reference changes less than it: clamped to 0.
    const std::vector<Image> still(3, makeImage(2, 2, 60));
    const auto frozen = temporalInstability(still, reference);
    ASSERT_TRUE(frozen.isOk());
    EXPECT_EQ(frozen->mean, 0.0);
    EXPECT_EQ(frozen->maxFrame, 0.0);
}

TEST(ImageMetricsTest, TemporalInstabilityRejectsBadSequences) {
    const Image frame = makeImage(2, 2, 0);
    const std::vector<Image> two(2, frame);
    const std::vector<Image> three(3, frame);
    EXPECT_EQ(temporalInstability(two, three).status().code(), ErrorCode::InvalidArgument);
    const std::vector<Image> one(1, frame);
    EXPECT_EQ(temporalInstability(one, one).status().code(), ErrorCode::InvalidArgument);

    std::vector<Image> resized = three;
    resized[2] = makeImage(3, 2, 0);
    // Both sequences change size together at frame 2: each frame matches its reference, but
    // frames 1 and 2 of one sequence differ.
    const auto status = temporalInstability(resized, resized).status();
    EXPECT_EQ(status.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(status.message().find("frames 1..2"), std::string::npos) << status.toString();
    EXPECT_EQ(
            temporalInstability(frame, frame, frame, makeImage(2, 3, 0)).status().code(),
            ErrorCode::InvalidArgument);
}

TEST(ImageMetricsTest, AccumulatorIsZeroBeforeAnyPair) {
    const TemporalInstability empty = TemporalInstabilityAccumulator{}.result();
    EXPECT_EQ(empty.framePairs, 0u);
    EXPECT_EQ(empty.mean, 0.0);
    EXPECT_EQ(empty.maxFrame, 0.0);
}

} // namespace
} // namespace ff::runtime
