// Image quality metrics as NeRF / TensoRF papers report them.
#ifndef ECRF_TRAINER_DATA_IMAGE_METRICS_H_
#define ECRF_TRAINER_DATA_IMAGE_METRICS_H_

#include "trainer/data/image_io.h"

namespace ecrf::trainer {

// Mean squared error over the colour channels (the first min(3, channels); alpha is ignored)
// of two images with the same size and channel count, values in [0, 1].
double MeanSquaredError(const Image& a, const Image& b);

// -10 log10(MSE) over the colour channels. Identical images give +infinity.
// Throws std::runtime_error if the shapes differ.
double Psnr(const Image& a, const Image& b);

// Columns [x0, width) of `image` (all rows and channels): the scored part of a view whose left
// columns fitted its camera (View::fitted_columns). x0 <= 0: the image itself.
Image ColumnsFrom(const Image& image, int x0);

// Structural similarity (Wang et al. 2004) exactly as TensoRF's rgb_ssim computes it: 11x11
// Gaussian window with sigma 1.5 applied separably with 'valid' borders, C1 = 0.01^2,
// C2 = 0.03^2 (data range 1), variances clipped at 0, averaged over the valid pixels and the
// colour channels. Both sides must be at least 11 pixels. Identical images give exactly 1.
double Ssim(const Image& a, const Image& b);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_IMAGE_METRICS_H_
