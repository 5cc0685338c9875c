"""The numerical engine: geometry, optical depth and the scattering integrals."""
