"""Analytic and empirical sky models (CIE, ASRC-CIE, Perez, Preetham, ...)."""
