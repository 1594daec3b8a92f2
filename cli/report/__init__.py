"""Per-BRDF accuracy reports and batch processing over BRDF libraries."""
