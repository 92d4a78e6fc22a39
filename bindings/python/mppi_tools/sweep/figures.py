"""The figures of a closed-loop run from its summary (summary.json / RunSummary.to_json()):
what the run computed, the same to the bit for the same settings and seed (the optimizer's wall
times are kept apart, as wall_* figures)."""
import math


def _finite(values):
    return [v for v in values if v is not None and math.isfinite(v)]


def run_figures(summary):
    laps = _finite(summary.get('lap_times_s') or [])
    ratios = _finite(summary.get('lap_time_ratio') or [])
    limit = summary.get('limit_lap_s')
    return {
        'finished': bool(summary['finished']),
        'laps_completed': int(summary['laps_completed']),
        'crashes': int(summary['crashes']),
        'stalls': int(summary['stalls']),
        'lap_times_s': laps,
        'mean_lap_s': sum(laps) / len(laps) if laps else float('nan'),
        'limit_lap_s': limit if limit is not None else float('nan'),
        # each lap over its limit lap: lap 1 (from rest) over standing_limit_lap_s, the others limit_lap_s
        'mean_lap_over_limit': sum(ratios) / len(ratios) if ratios else float('nan'),
        'mean_speed_mps': summary.get('mean_speed_mps'),
        'max_speed_mps': summary.get('max_speed_mps'),
        'peak_slip_deg': math.degrees(summary['peak_slip_angle_rad']) if summary.get('peak_slip_angle_rad') is not None
        else float('nan'),
        'sim_time_s': summary.get('sim_time_s'),
        'wall_optimizer_ms_p50': summary.get('optimizer_ms_p50'),
    }
