"""The one error type of mppi_tools: a message that names what went wrong and where."""


class ToolError(RuntimeError):
    """A bad setting, an unreachable scheduler, a missing program: the message says which."""
