"""Benchmark harness: run policies over test worlds and report statistics."""
