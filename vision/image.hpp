// vision/image: loading an image, its grey levels, and the backdrop estimate (flat field).
//
// Design note. Everything vision measures is a contrast against the backdrop. Lab photos have
// uneven lighting (a lamp on one side, vignetting) and renders may too, so a fixed grey threshold
// would move the silhouette with the light. We therefore divide the grey image by an estimate of
// the backdrop: either an image of the empty scene given by the caller (background difference)
// or a smooth low-order polynomial surface fitted to the pixels that look like backdrop. After
// this "flat field" the backdrop reads about 1.0 everywhere and the pile about its reflectance
// ratio (0.5 for the rock grey of the renders), so one threshold and one 50% edge level hold
// over the whole image. A polynomial (not a large blur) is used because the pile may fill half
// the image: a blur would leak the pile into its own backdrop estimate.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace reposetwin::vision {

/// Limits on an image before it is decoded: a photo far beyond any lab camera's would take
/// seconds and gigabytes to decode before vision could say anything about it, and a sliver a few
/// pixels high holds no pile to measure.
struct ImageLimits {
  double max_pixels = 250e6;  // width x height; a 100-megapixel camera's frame is 1e8 [px]
  int min_side_px = 16;       // the shorter side [px]
};

/// Width and height read from a PNG, JPEG or BMP file's header without decoding it (OpenCV 4.6,
/// Debian 12's, has no call that reads a size without decoding, and its own pixel limit is read
/// from the environment once at start-up); std::nullopt
/// for another format or a header too short to read. Throws std::invalid_argument naming `path`
/// when the file cannot be opened.
std::optional<cv::Size> image_header_size(const std::string& path);

/// Reads an image file as 8-bit BGR. Throws std::invalid_argument naming `path` when the file is
/// missing, is not an image OpenCV can decode, or is empty, and naming the limit when its size
/// (read from the header before decoding where the format allows, else after) is outside
/// `limits`.
cv::Mat load_image(const std::string& path, const ImageLimits& limits = {});

/// Grey levels of an 8-bit or 16-bit image with 1, 3 or 4 channels, as CV_32F scaled to
/// [0, 255]. Throws std::invalid_argument naming `where` for an empty or unsupported image.
cv::Mat gray_levels(const cv::Mat& image, const std::string& where = "image");

/// Throws std::invalid_argument naming `where` when the grey image has no usable contrast: all
/// black, or nearly uniform (spread between the 1st and 99th percentile below `min_contrast`
/// grey levels).
void check_contrast(const cv::Mat& gray, const std::string& where = "image",
                    double min_contrast = 10.0);

/// How the backdrop level is estimated when no image of the empty scene is given.
struct FlatFieldSettings {
  int degree = 2;               // degree of the polynomial surface in u and v (0 = a constant) [-]
  int work_width_px = 240;      // the fit runs on a copy downsampled to this width [px]
  double backdrop_band = 0.25;  // a pixel counts as backdrop within this fraction of the fit [-]
  int iterations = 3;           // refits after reclassifying backdrop pixels [-]
};

/// Estimates the backdrop's grey level at every pixel (CV_32F, same size as `gray`), assuming the
/// objects of interest are darker than the backdrop: the first classification is Otsu's bright
/// class, refined by refitting. Throws std::runtime_error naming `where` if no backdrop is found.
cv::Mat estimate_backdrop(const cv::Mat& gray, const FlatFieldSettings& settings = {},
                          const std::string& where = "image");

/// The flat-fielded image: gray / backdrop (CV_32F, backdrop about 1). `backdrop` may be an
/// image of the empty scene (any type `gray_levels` accepts, same size) or empty, in which case
/// it is estimated with `estimate_backdrop`.
cv::Mat flat_field(const cv::Mat& gray, const cv::Mat& backdrop, const FlatFieldSettings& settings,
                   const std::string& where = "image");

/// Otsu's threshold of a CV_32F image over the values in [lo, hi] (histogram of 256 bins).
/// The 256-bin histogram (CV_32F, 256 x 1) of a grey image converted to 8 bits.
cv::Mat histogram256(const cv::Mat& gray);

double otsu_threshold(const cv::Mat& values, double lo, double hi, const cv::Mat& mask = cv::Mat());

}  // namespace reposetwin::vision
