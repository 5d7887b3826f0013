"""The test suite (a package, so that pytest puts the checkout, not tests/, on sys.path)."""
