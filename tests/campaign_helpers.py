"""The slow Monte Carlo tests' one call of the campaign runner (navfmu montecarlo)."""
from __future__ import annotations

import os
from pathlib import Path

from orchestrator.campaigns.campaign import Campaign, CampaignSpec, run_campaign
from direct_replay import MODELS


def run_paper_campaign(scenario, filters, runs, out, seed_offsets, stop_time=None):
    """Run ``runs`` seeds x ``filters`` of ``models/<scenario>`` on the direct backend with
    metrics at the GNSS fix epochs (``NAVFMU_MC_WORKERS`` processes, default 2); returns
    (filter -> per-run records, the campaign summary)."""
    spec = CampaignSpec(scenario=str(MODELS / scenario), filters=tuple(filters), runs=runs,
                        seed=1, samples="fixes", seed_offsets=tuple(seed_offsets),
                        stop_time=stop_time)
    workers = int(os.environ.get("NAVFMU_MC_WORKERS", "2"))
    summary = run_campaign(spec, out, workers=workers, log=print)
    campaign = Campaign(spec, Path(out))
    campaign.prepare()
    return campaign.records(), summary
