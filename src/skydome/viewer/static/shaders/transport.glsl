// Scalar functions of skydome.transport._kernels shared by the physically based shaders
// (PI is defined by the program that includes this file).
const float INV_4PI = 1.0 / (4.0 * PI);

// profile_density: density relative to the reference density at altitude h [m] ([KRZ06] eq. 7)
float profile_density(int code, float p0, float p1, float h) {
    if (code == 0) return exp(-max(h, 0.0) / p0);                   // exponential
    if (code == 1) return max(0.0, 1.0 - abs(h - p0) / p1);          // tent
    if (code == 2) return h < p0 ? 1.0 : 0.0;                        // uniform
    if (code == 3) { float x = (h - p0) / p1; return exp(-0.5 * x * x); }  // gaussian
    return 0.0;
}

// phase_value: phase function normalised over the sphere [sr^-1]: Rayleigh (depolarised,
// param = rho / (2 - rho)), Henyey-Greenstein, Cornette-Shanks, isotropic
float phase_value(int code, float param, float c) {
    if (code == 0) return 3.0 / (16.0 * PI) / (1.0 + 2.0 * param) * ((1.0 + 3.0 * param) + (1.0 - param) * c * c);
    if (code == 1) { float g = param, d = 1.0 + g * g - 2.0 * g * c; return (1.0 - g * g) / (d * sqrt(d)) * INV_4PI; }
    if (code == 2) { float g = param, d = 1.0 + g * g - 2.0 * g * c;
                     return 3.0 * (1.0 - g * g) / (2.0 * (2.0 + g * g)) * (1.0 + c * c) / (d * sqrt(d)) * INV_4PI; }
    return INV_4PI;
}
