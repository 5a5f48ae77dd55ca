"""Campaigns: TOML schema, plan (cases and ids), store (folders + index), executors, runner."""
