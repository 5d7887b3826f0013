"""Small scenes, bad inputs and stress cases shared by the tests, the benchmarks and the docs."""
