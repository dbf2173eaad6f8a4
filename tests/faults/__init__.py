"""Fault-injection tests: broken inputs built in tmp_path must fail loudly, in one line."""
