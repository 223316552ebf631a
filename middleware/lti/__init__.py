"""LTI 1.3 Advantage: Telelab as a tool an LMS launches (pylti1p3), with deep linking, grades and rosters."""
