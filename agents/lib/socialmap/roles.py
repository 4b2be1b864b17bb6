"""Per-role scale of the personal space (the framework seed's future work, section 7).

Why a scale and not per-role sigmas: the seed's asymmetry (ahead > sides > behind) is the
cross-cultural shape it cites; what changes with familiarity is the size. Staff approach residents
all day and accept a closer robot; a newly admitted resident does not know the robot yet.
The numbers are our choice (the seed gives none) and are configurable.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, field_validator

from agents.lib.socialmap.types import Person, SocialMapInputError

DEFAULT_ROLE_SCALES: dict[str, float] = {
    "resident": 1.0,
    "new_resident": 1.25,
    "staff": 0.75,
    "therapist": 0.75,
    "visitor": 1.0,
}


class RoleParams(BaseModel):
    """Multiplier of every sigma per role. An unknown role is an input error, not a silent 1.0."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    scales: dict[str, float] = Field(default_factory=lambda: dict(DEFAULT_ROLE_SCALES))

    @field_validator("scales")
    @classmethod
    def _positive(cls, value: dict[str, float]) -> dict[str, float]:
        for role, scale in value.items():
            if not scale > 0.0:
                raise ValueError(f"scale of role {role!r} must be > 0, got {scale}")
        return value


def role_scale(person: Person, params: RoleParams) -> float:
    """The sigma multiplier of ``person``; raises SocialMapInputError naming person and role."""
    try:
        return params.scales[person.role]
    except KeyError:
        raise SocialMapInputError(f"person {person.name!r}: unknown role {person.role!r}; "
                                  f"known roles: {sorted(params.scales)}") from None
