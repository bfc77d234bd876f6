//! Pre-processing of real scanner range data (paper 000, sec. 4.1): hole filling, sky
//! detection, horizon margin (distance transform + Jacobi) and airlight estimation.
