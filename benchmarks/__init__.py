"""Benchmarks that measure the product's quality figures and print them against their targets."""
