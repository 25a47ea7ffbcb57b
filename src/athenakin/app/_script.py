"""The app's one channel for page scripts: viser's ``RunJavascriptMessage``.

viser 1.1 offers no public call that runs a script in the page; its own plotly element
sends one through the GUI's websocket interface. The app needs three such scripts (the
page title with the camera keys kept off the controls, the panel's scroll bar, and the
held clutch key of the Teleop tab), so this module is the one place that reaches into
viser's private ``_websock_interface`` and ``_messages``. A viser without them gives a
named error that says which version the app was written against.
"""

from __future__ import annotations

from typing import Any

__all__ = ["run_page_script"]


def run_page_script(server: Any, source: str) -> None:
    """Run ``source`` (JavaScript) in every page of ``server``, and in pages opened later.

    Parameters
    ----------
    server : viser.ViserServer
        The app's server.
    source : str
        The script, run by the page as ``new Function(source)()``.

    Returns
    -------
    None

    Raises
    ------
    ImportError
        The installed viser has no page-script channel (the app was written against
        viser 1.1), with ``name="viser"``.
    """
    try:
        from viser import _messages

        send = server.gui._websock_interface.queue_message
        message = _messages.RunJavascriptMessage(source=source)
    except (ImportError, AttributeError) as exc:
        raise ImportError(
            f"athenakin.app's page scripts need viser 1.1's RunJavascriptMessage channel, "
            f"which this viser does not have ({exc}); pip install 'viser>=1.1,<1.2'",
            name="viser") from exc
    send(message)
