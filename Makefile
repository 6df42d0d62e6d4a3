# cstep — `make test` runs every check CI runs; `.ci/run` calls exactly this.
CARGO ?= cargo

.PHONY: test lint test-rust bench

test: lint test-rust

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --all-targets --quiet -- -D warnings

test-rust:
	$(CARGO) test --all-targets

bench:
	$(CARGO) run --release --quiet -- bench
	$(CARGO) bench --bench evaluate
