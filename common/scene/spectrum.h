/* spectrum.h: spectra written in scene files (wavelength:value lists, blackbody emitters)
 * turned into the linear Rec. 709 RGB that pcbpt renders, exactly as Mitsuba 0.6 does in its
 * RGB mode: the spectrum is integrated against the CIE 1931 colour matching functions over
 * 360..830 nm, divided by the integral of y-bar, and the XYZ converted to RGB with negative
 * channels clamped to zero. */
#ifndef PC_SPECTRUM_H
#define PC_SPECTRUM_H

#define PC_CIE_SAMPLES 95   /* 360..830 nm every 5 nm */
#define PC_CIE_MIN 360.0
#define PC_CIE_STEP 5.0
#define PC_SPECTRUM_MAX_SAMPLES 1024

extern const double pc_cie1931[3][PC_CIE_SAMPLES]; /* x-bar, y-bar, z-bar */

/* A spectrum given at n >= 2 strictly increasing wavelengths (nm), linear between them and
 * extended by a zero one average spacing beyond each end when the end value is not zero
 * (Mitsuba's InterpolatedSpectrum::zeroExtend). Returns 0, or -1 if n < 2, n is above
 * PC_SPECTRUM_MAX_SAMPLES or the wavelengths do not increase. */
int pc_spectrum_sampled_rgb(const double *lambda_nm, const double *value, int n, double rgb[3]);
/* Planck's law at temperature kelvin, in W m^-2 sr^-1 nm^-1 (Mitsuba's BlackBodySpectrum). */
double pc_blackbody(double kelvin, double lambda_nm);
/* The RGB of a black body (before Mitsuba's `scale`). */
void pc_spectrum_blackbody_rgb(double kelvin, double rgb[3]);
/* CIE XYZ to linear Rec. 709 RGB (Mitsuba's Spectrum::fromXYZ), without clamping. */
void pc_xyz_to_rgb(const double xyz[3], double rgb[3]);

#endif
