// The real spherical-harmonics basis of the spherical-harmonics colour (HEAD hidden 0, SPEC.md
// 7.6.2), up to degree 3, in the order and with the constants of Plenoxels and 3D Gaussian
// splatting (so coefficients carry over). Every operation is one binary32 operation in the order
// written (the decoder builds with -ffp-contract=off), so the values are the SPEC's bits; the
// trainer uses the same function.
#ifndef ECRF_DECODER_SH_BASIS_H_
#define ECRF_DECODER_SH_BASIS_H_

namespace ecrf {

// (degree + 1)^2 functions for degrees 0..3.
inline constexpr int kMaxShFunctions = 16;

// y[0 .. (degree + 1)^2 - 1] = the basis at the unit direction d.
inline void ShBasis(const float d[3], int degree, float* y) {
  const float x = d[0], yv = d[1], z = d[2];
  y[0] = 0.28209479177387814f;
  if (degree < 1) return;
  y[1] = -0.4886025119029199f * yv;
  y[2] = 0.4886025119029199f * z;
  y[3] = -0.4886025119029199f * x;
  if (degree < 2) return;
  const float xx = x * x, yy = yv * yv, zz = z * z;
  const float xy = x * yv, yz = yv * z, xz = x * z;
  y[4] = 1.0925484305920792f * xy;
  y[5] = -1.0925484305920792f * yz;
  y[6] = 0.31539156525252005f * ((2.f * zz - xx) - yy);
  y[7] = -1.0925484305920792f * xz;
  y[8] = 0.5462742152960396f * (xx - yy);
  if (degree < 3) return;
  y[9] = (-0.5900435899266435f * yv) * (3.f * xx - yy);
  y[10] = (2.890611442640554f * xy) * z;
  y[11] = (-0.4570457994644658f * yv) * ((4.f * zz - xx) - yy);
  y[12] = (0.3731763325901154f * z) * ((2.f * zz - 3.f * xx) - 3.f * yy);
  y[13] = (-0.4570457994644658f * x) * ((4.f * zz - xx) - yy);
  y[14] = (1.445305721320277f * z) * (xx - yy);
  y[15] = (-0.5900435899266435f * x) * (xx - 3.f * yy);
}

}  // namespace ecrf

#endif  // ECRF_DECODER_SH_BASIS_H_
