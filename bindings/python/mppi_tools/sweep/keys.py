"""A task's key: a hash of its kind and settings, the same on every machine and every run."""
import hashlib
import json


def canonical(settings):
    """The settings as canonical JSON text (sorted keys, no spaces); ValueError for a value JSON lacks."""
    return json.dumps(settings, sort_keys=True, separators=(',', ':'), allow_nan=False)


def task_key(kind, settings):
    """16 hex digits of SHA-256 over the task kind and its canonical settings."""
    return hashlib.sha256(f'{kind}\n{canonical(settings)}'.encode()).hexdigest()[:16]
