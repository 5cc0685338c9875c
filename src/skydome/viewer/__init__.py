"""``skydome view``: a local server and a WebGL2 page that render skydome's models live.

The physics stays in Python: :mod:`skydome.viewer.scene` builds each model with skydome's
own code and turns it into the numbers a shader needs (coefficients, per-wavelength
tables, CIE weights); the shaders in ``static/`` are the real-time evaluators and mirror
the scalar functions of the CPU kernels. :mod:`skydome.viewer.server` serves the page and
those numbers on 127.0.0.1 only.
"""

__all__: list[str] = []
