#include "vision/image.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::str;

// Monomials x^i y^j with i + j <= degree, ordered by degree, at normalised coordinates.
void monomials(double x, double y, int degree, float* out) {
  int k = 0;
  for (int d = 0; d <= degree; ++d) {
    for (int i = d; i >= 0; --i) {
      double v = 1.0;
      for (int e = 0; e < i; ++e) v *= x;
      for (int e = 0; e < d - i; ++e) v *= y;
      out[k++] = static_cast<float>(v);
    }
  }
}

int monomial_count(int degree) { return (degree + 1) * (degree + 2) / 2; }

// Big-endian and little-endian unsigned integers from a byte buffer.
std::uint32_t be(const unsigned char* b, int n) {
  std::uint32_t v = 0;
  for (int k = 0; k < n; ++k) v = (v << 8) | b[k];
  return v;
}
std::uint32_t le(const unsigned char* b, int n) {
  std::uint32_t v = 0;
  for (int k = n - 1; k >= 0; --k) v = (v << 8) | b[k];
  return v;
}

// A JPEG's frame size: the first start-of-frame marker (SOF0..SOF15 but DHT C4, JPG C8 and DAC
// CC), each segment skipped by its stated length.
std::optional<cv::Size> jpeg_size(std::ifstream& in) {
  unsigned char b[9];
  in.seekg(2);
  while (in.read(reinterpret_cast<char*>(b), 4)) {
    if (b[0] != 0xFF) return std::nullopt;
    const int marker = b[1];
    const std::uint32_t length = be(b + 2, 2);
    if (length < 2) return std::nullopt;
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 &&
                     marker != 0xCC;
    if (sof) {
      if (!in.read(reinterpret_cast<char*>(b), 5)) return std::nullopt;
      return cv::Size(static_cast<int>(be(b + 3, 2)), static_cast<int>(be(b + 1, 2)));
    }
    in.seekg(static_cast<std::streamoff>(length) - 2, std::ios::cur);
  }
  return std::nullopt;
}

// Clamps a header field to int for cv::Size (a forged header may state up to 2^32 - 1).
int side(std::uint32_t v) {
  return static_cast<int>(std::min<std::uint32_t>(v, std::numeric_limits<int>::max()));
}

}  // namespace

std::optional<cv::Size> image_header_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open the image file");
  unsigned char h[26] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const std::streamsize got = in.gcount();
  in.clear();
  static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (got >= 24 && std::equal(kPng, kPng + 8, h) && std::equal(h + 12, h + 16, "IHDR"))
    return cv::Size(side(be(h + 16, 4)), side(be(h + 20, 4)));
  if (got >= 26 && h[0] == 'B' && h[1] == 'M') {  // BITMAPINFOHEADER: signed, height may be < 0
    const auto w = static_cast<std::int32_t>(le(h + 18, 4));
    const auto hh = static_cast<std::int32_t>(le(h + 22, 4));
    return cv::Size(side(static_cast<std::uint32_t>(std::abs(static_cast<std::int64_t>(w)))),
                    side(static_cast<std::uint32_t>(std::abs(static_cast<std::int64_t>(hh)))));
  }
  if (got >= 3 && h[0] == 0xFF && h[1] == 0xD8 && h[2] == 0xFF) return jpeg_size(in);
  return std::nullopt;
}

namespace {

void check_size(const std::string& path, cv::Size size, const ImageLimits& limits) {
  const double pixels = static_cast<double>(size.width) * static_cast<double>(size.height);
  if (pixels > limits.max_pixels)
    throw std::invalid_argument(path + ": image is " + std::to_string(size.width) + " x " +
                                std::to_string(size.height) + " pixels, above the limit of " +
                                str(limits.max_pixels) + " pixels (vision's image limit)");
  if (std::min(size.width, size.height) < limits.min_side_px)
    throw std::invalid_argument(path + ": image is " + std::to_string(size.width) + " x " +
                                std::to_string(size.height) + " pixels; both sides must be at "
                                "least " + std::to_string(limits.min_side_px) + " pixels");
}

}  // namespace

cv::Mat load_image(const std::string& path, const ImageLimits& limits) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument(path + ": image file does not exist or is not a regular file");
  if (const std::optional<cv::Size> header = image_header_size(path))
    check_size(path, *header, limits);
  cv::Mat img;
  try {
    img = cv::imread(path, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(path + ": cannot decode image (" + e.what() + ")");
  }
  if (img.empty())
    throw std::invalid_argument(path + ": not an image OpenCV can decode (or the image is empty)");
  check_size(path, img.size(), limits);  // formats whose header we do not read
  return img;
}

cv::Mat gray_levels(const cv::Mat& image, const std::string& where) {
  if (image.empty()) throw std::invalid_argument(where + ": image is empty (0 x 0 pixels)");
  const int depth = image.depth();
  if (depth != CV_8U && depth != CV_16U)
    throw std::invalid_argument(where + ": image depth must be 8 or 16 bit, got OpenCV depth " +
                                str(depth));
  cv::Mat gray;
  switch (image.channels()) {
    case 1:
      gray = image;
      break;
    case 3:
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      break;
    case 4:
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
      break;
    default:
      throw std::invalid_argument(where + ": image must have 1, 3 or 4 channels, got " +
                                  str(image.channels()));
  }
  cv::Mat out;
  gray.convertTo(out, CV_32F, depth == CV_16U ? 255.0 / 65535.0 : 1.0);
  return out;
}

void check_contrast(const cv::Mat& gray, const std::string& where, double min_contrast) {
  if (gray.empty()) throw std::invalid_argument(where + ": image is empty (0 x 0 pixels)");
  // Percentiles from a subsample of at most about 500 px across are plenty.
  cv::Mat sub = gray;
  const int step = std::max(1, std::max(gray.cols, gray.rows) / 500);
  if (step > 1) cv::resize(gray, sub, cv::Size(), 1.0 / step, 1.0 / step, cv::INTER_NEAREST);
  const cv::Mat hist = histogram256(sub);
  const double total = static_cast<double>(sub.total());
  double cum = 0.0;
  int p1 = -1, p99 = 255;
  for (int i = 0; i < 256; ++i) {
    cum += hist.at<float>(i);
    if (p1 < 0 && cum >= 0.01 * total) p1 = i;
    if (cum >= 0.99 * total) {
      p99 = i;
      break;
    }
  }
  double max_level = 0.0;
  cv::minMaxLoc(gray, nullptr, &max_level);
  if (max_level < min_contrast)
    throw std::invalid_argument(where + ": image is all black (brightest grey level " +
                                str(max_level) + ")");
  if (p99 - p1 < min_contrast)
    throw std::invalid_argument(where +
                                ": image has no contrast (grey levels 1st-99th percentile " +
                                str(p1) + ".." + str(p99) + ")");
}

cv::Mat histogram256(const cv::Mat& gray) {
  cv::Mat g8;
  gray.convertTo(g8, CV_8U);
  const int channels[] = {0};
  const int bins[] = {256};
  const float range[] = {0.f, 256.f};
  const float* ranges[] = {range};
  cv::Mat hist;
  cv::calcHist(&g8, 1, channels, cv::Mat(), hist, 1, bins, ranges);
  return hist;
}

double otsu_threshold(const cv::Mat& values, double lo, double hi, const cv::Mat& mask) {
  CV_Assert(values.type() == CV_32F && hi > lo);
  // A regular subsample of about 250k values gives the same histogram shape, faster.
  const int step = std::max(1, static_cast<int>(std::sqrt(values.total() / 250000.0)));
  cv::Mat sub = values, sub_mask = mask;
  if (step > 1) {
    cv::resize(values, sub, cv::Size(), 1.0 / step, 1.0 / step, cv::INTER_NEAREST);
    if (!mask.empty())
      cv::resize(mask, sub_mask, cv::Size(), 1.0 / step, 1.0 / step, cv::INTER_NEAREST);
  }
  cv::Mat v8;
  sub.convertTo(v8, CV_8U, 255.0 / (hi - lo), -lo * 255.0 / (hi - lo));
  cv::Mat samples;
  if (sub_mask.empty()) {
    samples = v8.isContinuous() ? v8.reshape(1, 1) : v8.clone().reshape(1, 1);
  } else {
    std::vector<uchar> kept;
    kept.reserve(static_cast<size_t>(cv::countNonZero(sub_mask)));
    for (int r = 0; r < v8.rows; ++r) {
      const uchar* m = sub_mask.ptr<uchar>(r);
      const uchar* p = v8.ptr<uchar>(r);
      for (int c = 0; c < v8.cols; ++c)
        if (m[c]) kept.push_back(p[c]);
    }
    if (kept.empty()) return 0.5 * (lo + hi);
    samples = cv::Mat(kept, true).reshape(1, 1);
  }
  cv::Mat dummy;
  const double t8 = cv::threshold(samples, dummy, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  return lo + (t8 + 0.5) * (hi - lo) / 255.0;
}

cv::Mat estimate_backdrop(const cv::Mat& gray, const FlatFieldSettings& s,
                          const std::string& where) {
  if (s.degree < 0 || s.degree > 4)
    throw std::invalid_argument(where + ": flat_field.degree must be 0..4, got " + str(s.degree));
  if (s.work_width_px < 16)
    throw std::invalid_argument(where + ": flat_field.work_width_px must be >= 16, got " +
                                str(s.work_width_px));
  const double scale = std::min(1.0, static_cast<double>(s.work_width_px) / gray.cols);
  cv::Mat small;
  cv::resize(gray, small, cv::Size(), scale, scale, cv::INTER_AREA);
  if (small.empty()) throw std::runtime_error(where + ": image too small for a backdrop estimate");

  // First guess: Otsu's bright class is the backdrop.
  const double t = otsu_threshold(small, 0.0, 256.0);
  cv::Mat is_backdrop = small > t;
  const int nk = monomial_count(s.degree);
  // Monomials of every pixel of the small image (normalised coordinates in [-1, 1]).
  cv::Mat design(small.rows * small.cols, nk, CV_32F);
  for (int r = 0; r < small.rows; ++r) {
    for (int c = 0; c < small.cols; ++c) {
      const double x = small.cols > 1 ? 2.0 * c / (small.cols - 1) - 1.0 : 0.0;
      const double y = small.rows > 1 ? 2.0 * r / (small.rows - 1) - 1.0 : 0.0;
      monomials(x, y, s.degree, design.ptr<float>(r * small.cols + c));
    }
  }
  const cv::Mat values = small.reshape(1, small.rows * small.cols);
  cv::Mat fit;
  for (int it = 0; it <= s.iterations; ++it) {
    // Normal equations over the backdrop pixels (nk <= 15 unknowns).
    const cv::Mat flags = is_backdrop.reshape(1, small.rows * small.cols);
    cv::Mat ata = cv::Mat::zeros(nk, nk, CV_64F), atb = cv::Mat::zeros(nk, 1, CV_64F);
    int n = 0;
    for (int i = 0; i < flags.rows; ++i) {
      if (!flags.at<uchar>(i)) continue;
      const float* m = design.ptr<float>(i);
      const double v = values.at<float>(i);
      for (int p = 0; p < nk; ++p) {
        double* row = ata.ptr<double>(p);
        for (int q = 0; q <= p; ++q) row[q] += static_cast<double>(m[p]) * m[q];
        atb.at<double>(p) += m[p] * v;
      }
      ++n;
    }
    if (n < 4 * nk)
      throw std::runtime_error(where + ": no backdrop found (only " + str(n) +
                               " bright pixels in the downsampled image)");
    for (int p = 0; p < nk; ++p)
      for (int q = p + 1; q < nk; ++q) ata.at<double>(p, q) = ata.at<double>(q, p);
    cv::Mat coef;
    cv::solve(ata, atb, coef, cv::DECOMP_SVD);
    coef.convertTo(coef, CV_32F);
    fit = cv::Mat(design * coef).reshape(1, small.rows);
    if (it == s.iterations) break;
    cv::Mat rel;
    cv::absdiff(small, fit, rel);
    is_backdrop = rel < s.backdrop_band * cv::max(fit, 1.0);
  }
  cv::Mat full;
  cv::resize(fit, full, gray.size(), 0, 0, cv::INTER_LINEAR);
  return cv::max(full, 1.0);
}

cv::Mat flat_field(const cv::Mat& gray, const cv::Mat& backdrop, const FlatFieldSettings& settings,
                   const std::string& where) {
  cv::Mat level;
  if (backdrop.empty()) {
    level = estimate_backdrop(gray, settings, where);
  } else {
    level = gray_levels(backdrop, where + ": backdrop image");
    if (level.size() != gray.size())
      throw std::invalid_argument(where + ": backdrop image is " + str(level.cols) + "x" +
                                  str(level.rows) + " but the image is " + str(gray.cols) + "x" +
                                  str(gray.rows));
    level = cv::max(level, 1.0);
  }
  cv::Mat out;
  cv::divide(gray, level, out);
  return out;
}

}  // namespace reposetwin::vision
