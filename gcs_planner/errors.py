"""Errors a user sees. The command line turns each into one line on stderr and an exit code."""

from __future__ import annotations


class GcsPlannerError(Exception):
    """Base of every error the command line reports without a traceback."""

    exit_code = 2


class InputError(GcsPlannerError):
    """Bad input: names the file and, where it applies, the row and the field."""

    exit_code = 2

    def __init__(
        self, message: str, *, file: str = "", row: int | None = None, field: str | None = None
    ) -> None:
        self.file = file
        self.row = row
        self.field = field
        self.reason = message
        where = [file] if file else []
        if row is not None:
            where.append(f"row {row}")
        if field is not None:
            where.append(f"field {field!r}")
        super().__init__(f"{', '.join(where)}: {message}" if where else message)


class InfeasibleError(GcsPlannerError):
    """The scenario has no feasible route; the message says why."""

    exit_code = 3


class LinkError(GcsPlannerError):
    """A MAVLink transfer failed or the vehicle refused it."""

    exit_code = 4


class UploadRefused(LinkError):
    """The vehicle answered an upload with a refusal (a MISSION_ACK other than ACCEPTED, or an
    FTP mission file it did not store): what it holds is unchanged, unlike an upload the link
    lost part-way, so a caller may go on with the mission the vehicle still flies."""
