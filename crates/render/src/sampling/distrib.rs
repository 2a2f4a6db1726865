//! Discrete and piecewise-constant 1D/2D distributions (light selection by power, environment
//! map importance sampling). TO BE WRITTEN (helper: sampling/film).
