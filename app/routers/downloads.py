"""The one way a route answers with a file download."""

from __future__ import annotations

from fastapi import Response

from app.services import ExportFile


def download(export: ExportFile) -> Response:
    """Answer ``export`` as an attachment named after its file (``Content-Disposition``)."""
    return Response(
        content=export.content,
        media_type=export.media_type,
        headers={"Content-Disposition": f'attachment; filename="{export.filename}"'},
    )
