//! Statistical tests used by the test suite and by `penumbra test`: χ² goodness of fit of a
//! sampling routine against its pdf, Student's t-test. TO BE WRITTEN (helper: bsdf).
