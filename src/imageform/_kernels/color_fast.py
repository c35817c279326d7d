"""placeholder"""

from typing import Any


def dispatch(image: Any, s: str, d: str, p: dict[str, Any]) -> Any:
    return None
