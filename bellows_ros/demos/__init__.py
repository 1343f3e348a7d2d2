"""Runnable demonstrations (`python -m bellows_ros.demos.<name>`)."""
