#include "trainer/data/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace ecrf::trainer {
namespace {

constexpr int kSsimWindow = 11;
constexpr double kSsimSigma = 1.5;
constexpr double kSsimC1 = 0.01 * 0.01;
constexpr double kSsimC2 = 0.03 * 0.03;

void CheckSameShape(const Image& a, const Image& b, const char* metric) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
    throw std::runtime_error(std::string(metric) + ": images differ in shape (" +
                             std::to_string(a.width) + "x" + std::to_string(a.height) + "x" +
                             std::to_string(a.channels) + " vs " + std::to_string(b.width) + "x" +
                             std::to_string(b.height) + "x" + std::to_string(b.channels) + ")");
  }
  if (a.width <= 0 || a.height <= 0 || a.channels <= 0)
    throw std::runtime_error(std::string(metric) + ": empty image");
}

int ColourChannels(const Image& image) { return std::min(3, image.channels); }

std::vector<double> GaussianWindow() {
  std::vector<double> weights(kSsimWindow);
  double sum = 0;
  for (int i = 0; i < kSsimWindow; ++i) {
    const double x = (i - kSsimWindow / 2) / kSsimSigma;
    weights[i] = std::exp(-0.5 * x * x);
    sum += weights[i];
  }
  for (double& w : weights) w /= sum;
  return weights;
}

// 'valid' separable filtering of a width x height plane: out is (w - 10) x (h - 10).
// The window is symmetric, so convolution and correlation agree.
std::vector<double> FilterValid(const std::vector<double>& plane, int width, int height,
                                const std::vector<double>& window) {
  const int out_w = width - kSsimWindow + 1, out_h = height - kSsimWindow + 1;
  std::vector<double> rows(static_cast<size_t>(out_h) * width);
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < width; ++x) {
      double sum = 0;
      for (int k = 0; k < kSsimWindow; ++k)
        sum += window[k] * plane[static_cast<size_t>(y + k) * width + x];
      rows[static_cast<size_t>(y) * width + x] = sum;
    }
  }
  std::vector<double> out(static_cast<size_t>(out_h) * out_w);
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      double sum = 0;
      for (int k = 0; k < kSsimWindow; ++k)
        sum += window[k] * rows[static_cast<size_t>(y) * width + x + k];
      out[static_cast<size_t>(y) * out_w + x] = sum;
    }
  }
  return out;
}

}  // namespace

double MeanSquaredError(const Image& a, const Image& b) {
  CheckSameShape(a, b, "MSE");
  const int colours = ColourChannels(a);
  const size_t count = static_cast<size_t>(a.width) * a.height;
  double sum = 0;
  for (size_t p = 0; p < count; ++p) {
    for (int c = 0; c < colours; ++c) {
      const double d =
          static_cast<double>(a.pixels[p * a.channels + c]) - b.pixels[p * b.channels + c];
      sum += d * d;
    }
  }
  return sum / (static_cast<double>(count) * colours);
}

double Psnr(const Image& a, const Image& b) {
  CheckSameShape(a, b, "PSNR");
  const double mse = MeanSquaredError(a, b);
  if (mse == 0) return std::numeric_limits<double>::infinity();
  return -10.0 * std::log10(mse);
}

Image ColumnsFrom(const Image& image, int x0) {
  if (x0 <= 0) return image;
  x0 = std::min(x0, image.width);
  Image out = MakeImage(image.width - x0, image.height, image.channels);
  const size_t row = size_t(out.width) * image.channels;
  for (int y = 0; y < image.height; ++y) {
    std::copy_n(&image.pixels[(size_t(y) * image.width + x0) * image.channels], row,
                &out.pixels[size_t(y) * row]);
  }
  return out;
}

double Ssim(const Image& a, const Image& b) {
  CheckSameShape(a, b, "SSIM");
  if (a.width < kSsimWindow || a.height < kSsimWindow) {
    throw std::runtime_error("SSIM: images are " + std::to_string(a.width) + "x" +
                             std::to_string(a.height) +
                             ", need at least 11x11 for the 11x11 window");
  }
  const std::vector<double> window = GaussianWindow();
  const size_t count = static_cast<size_t>(a.width) * a.height;
  const int colours = ColourChannels(a);
  double total = 0;
  size_t valid_count = 0;
  std::vector<double> x(count), y(count), xx(count), yy(count), xy(count);
  for (int c = 0; c < colours; ++c) {
    for (size_t p = 0; p < count; ++p) {
      x[p] = a.pixels[p * a.channels + c];
      y[p] = b.pixels[p * b.channels + c];
      xx[p] = x[p] * x[p];
      yy[p] = y[p] * y[p];
      xy[p] = x[p] * y[p];
    }
    const std::vector<double> mu_x = FilterValid(x, a.width, a.height, window);
    const std::vector<double> mu_y = FilterValid(y, a.width, a.height, window);
    const std::vector<double> e_xx = FilterValid(xx, a.width, a.height, window);
    const std::vector<double> e_yy = FilterValid(yy, a.width, a.height, window);
    const std::vector<double> e_xy = FilterValid(xy, a.width, a.height, window);
    for (size_t p = 0; p < mu_x.size(); ++p) {
      const double mxx = mu_x[p] * mu_x[p], myy = mu_y[p] * mu_y[p], mxy = mu_x[p] * mu_y[p];
      // Clipping as TensoRF does: rounding can make E[x^2] - mu^2 slightly negative.
      const double var_x = std::max(0.0, e_xx[p] - mxx);
      const double var_y = std::max(0.0, e_yy[p] - myy);
      double cov = e_xy[p] - mxy;
      cov = std::copysign(std::min(std::sqrt(var_x * var_y), std::abs(cov)), cov);
      const double numerator = (2 * mxy + kSsimC1) * (2 * cov + kSsimC2);
      const double denominator = (mxx + myy + kSsimC1) * (var_x + var_y + kSsimC2);
      total += numerator / denominator;
    }
    valid_count += mu_x.size();
  }
  return total / static_cast<double>(valid_count);
}

}  // namespace ecrf::trainer
