"""Tracking stages. Every module here is imported by :func:`vtrack.stages.base.all_stages`; a
stage becomes available to configs by decorating its class with ``@register``."""
