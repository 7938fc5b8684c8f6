#!/usr/bin/python3
"""Independent reference for the tracking scores (test/adk/tracking_metrics_test.cpp).

Reads sequences of frames (ground-truth boxes with visible fraction and occlusion, reported
boxes) as JSON and writes every score as JSON. CLEAR-MOT, identity and HOTA follow TrackEval's
clear.py, identity.py and hota.py line by line (numpy, scipy's linear_sum_assignment); the
single-target scores follow UAV123's toolkit (precision at 20 px, success as the mean over IoU
thresholds 0, 0.05, ..., 1 of the fraction of frames above it).

usage: tracking_reference.py IN.json OUT.json
"""
import json
import sys

import numpy as np
from scipy.optimize import linear_sum_assignment

EPS = np.finfo('float').eps


def box_iou(a, b):
    iw = min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0])
    ih = min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1])
    inter = max(iw, 0.0) * max(ih, 0.0)
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


def centre_error(a, b):
    return float(np.hypot(a[0] + a[2] / 2 - b[0] - b[2] / 2, a[1] + a[3] / 2 - b[1] - b[3] / 2))


def to_trackeval(frames, mot_min_visible):
    """TrackEval's data dict: dense ids, per-timestep id arrays and IoU matrices."""
    gt_names = sorted({g['id'] for f in frames for g in f['targets']
                       if g['visible_fraction'] >= mot_min_visible})
    tr_names = sorted({r['id'] for f in frames for r in f['tracks']})
    gmap = {n: i for i, n in enumerate(gt_names)}
    tmap = {n: i for i, n in enumerate(tr_names)}
    data = {'gt_ids': [], 'tracker_ids': [], 'similarity_scores': [],
            'num_gt_ids': len(gt_names), 'num_tracker_ids': len(tr_names),
            'num_gt_dets': 0, 'num_tracker_dets': 0, 'gt_names': gt_names}
    for f in frames:
        gts = [g for g in f['targets'] if g['visible_fraction'] >= mot_min_visible]
        data['gt_ids'].append(np.array([gmap[g['id']] for g in gts], dtype=int))
        data['tracker_ids'].append(np.array([tmap[r['id']] for r in f['tracks']], dtype=int))
        sim = np.zeros((len(gts), len(f['tracks'])))
        for i, g in enumerate(gts):
            for j, r in enumerate(f['tracks']):
                sim[i, j] = box_iou(g['box'], r['box'])
        data['similarity_scores'].append(sim)
        data['num_gt_dets'] += len(gts)
        data['num_tracker_dets'] += len(f['tracks'])
    return data


def clear(data, threshold=0.5):
    res = {k: 0 for k in ['CLR_TP', 'CLR_FN', 'CLR_FP', 'IDSW', 'MOTP_sum']}
    num_gt_ids = data['num_gt_ids']
    gt_id_count = np.zeros(num_gt_ids)
    gt_matched_count = np.zeros(num_gt_ids)
    gt_frag_count = np.zeros(num_gt_ids)
    idsw_per_gt = np.zeros(num_gt_ids)
    prev_tracker_id = np.nan * np.zeros(num_gt_ids)
    prev_timestep_tracker_id = np.nan * np.zeros(num_gt_ids)
    for t, (gt_ids_t, tracker_ids_t) in enumerate(zip(data['gt_ids'], data['tracker_ids'])):
        if len(gt_ids_t) == 0:
            res['CLR_FP'] += len(tracker_ids_t)
            continue
        if len(tracker_ids_t) == 0:
            res['CLR_FN'] += len(gt_ids_t)
            gt_id_count[gt_ids_t] += 1
            continue
        similarity = data['similarity_scores'][t]
        score_mat = (tracker_ids_t[np.newaxis, :] == prev_timestep_tracker_id[gt_ids_t[:, np.newaxis]])
        score_mat = 1000 * score_mat + similarity
        score_mat[similarity < threshold - EPS] = 0
        match_rows, match_cols = linear_sum_assignment(-score_mat)
        actually_matched_mask = score_mat[match_rows, match_cols] > 0 + EPS
        match_rows = match_rows[actually_matched_mask]
        match_cols = match_cols[actually_matched_mask]
        matched_gt_ids = gt_ids_t[match_rows]
        matched_tracker_ids = tracker_ids_t[match_cols]
        prev_matched_tracker_ids = prev_tracker_id[matched_gt_ids]
        is_idsw = (np.logical_not(np.isnan(prev_matched_tracker_ids))) & (
            np.not_equal(matched_tracker_ids, prev_matched_tracker_ids))
        res['IDSW'] += np.sum(is_idsw)
        idsw_per_gt[matched_gt_ids[is_idsw]] += 1
        gt_id_count[gt_ids_t] += 1
        gt_matched_count[matched_gt_ids] += 1
        not_previously_tracked = np.isnan(prev_timestep_tracker_id)
        prev_tracker_id[matched_gt_ids] = matched_tracker_ids
        prev_timestep_tracker_id[:] = np.nan
        prev_timestep_tracker_id[matched_gt_ids] = matched_tracker_ids
        currently_tracked = np.logical_not(np.isnan(prev_timestep_tracker_id))
        gt_frag_count += np.logical_and(not_previously_tracked, currently_tracked)
        num_matches = len(matched_gt_ids)
        res['CLR_TP'] += num_matches
        res['CLR_FN'] += len(gt_ids_t) - num_matches
        res['CLR_FP'] += len(tracker_ids_t) - num_matches
        if num_matches > 0:
            res['MOTP_sum'] += sum(similarity[match_rows, match_cols])
    tracked_ratio = gt_matched_count[gt_id_count > 0] / gt_id_count[gt_id_count > 0]
    res['MT'] = int(np.sum(np.greater(tracked_ratio, 0.8)))
    res['PT'] = int(np.sum(np.greater_equal(tracked_ratio, 0.2))) - res['MT']
    res['ML'] = num_gt_ids - res['MT'] - res['PT']
    res['Frag'] = int(np.sum(np.subtract(gt_frag_count[gt_frag_count > 0], 1)))
    res['MOTA'] = (res['CLR_TP'] - res['CLR_FP'] - res['IDSW']) / np.maximum(
        1.0, res['CLR_TP'] + res['CLR_FN'])
    res['MOTP'] = res['MOTP_sum'] / np.maximum(1.0, res['CLR_TP'])
    res['IDSW_per_gt'] = {data['gt_names'][i]: int(idsw_per_gt[i]) for i in range(num_gt_ids)}
    return res


def identity(data, threshold=0.5):
    potential_matches_count = np.zeros((data['num_gt_ids'], data['num_tracker_ids']))
    gt_id_count = np.zeros(data['num_gt_ids'])
    tracker_id_count = np.zeros(data['num_tracker_ids'])
    for t, (gt_ids_t, tracker_ids_t) in enumerate(zip(data['gt_ids'], data['tracker_ids'])):
        matches_mask = np.greater_equal(data['similarity_scores'][t], threshold)
        match_idx_gt, match_idx_tracker = np.nonzero(matches_mask)
        potential_matches_count[gt_ids_t[match_idx_gt], tracker_ids_t[match_idx_tracker]] += 1
        gt_id_count[gt_ids_t] += 1
        tracker_id_count[tracker_ids_t] += 1
    num_gt_ids = data['num_gt_ids']
    num_tracker_ids = data['num_tracker_ids']
    fp_mat = np.zeros((num_gt_ids + num_tracker_ids, num_gt_ids + num_tracker_ids))
    fn_mat = np.zeros((num_gt_ids + num_tracker_ids, num_gt_ids + num_tracker_ids))
    fp_mat[num_gt_ids:, :num_tracker_ids] = 1e10
    fn_mat[:num_gt_ids, num_tracker_ids:] = 1e10
    for gt_id in range(num_gt_ids):
        fn_mat[gt_id, :num_tracker_ids] = gt_id_count[gt_id]
        fn_mat[gt_id, num_tracker_ids + gt_id] = gt_id_count[gt_id]
    for tracker_id in range(num_tracker_ids):
        fp_mat[:num_gt_ids, tracker_id] = tracker_id_count[tracker_id]
        fp_mat[tracker_id + num_gt_ids, tracker_id] = tracker_id_count[tracker_id]
    fn_mat[:num_gt_ids, :num_tracker_ids] -= potential_matches_count
    fp_mat[:num_gt_ids, :num_tracker_ids] -= potential_matches_count
    match_rows, match_cols = linear_sum_assignment(fn_mat + fp_mat)
    res = {}
    res['IDFN'] = int(fn_mat[match_rows, match_cols].sum())
    res['IDFP'] = int(fp_mat[match_rows, match_cols].sum())
    res['IDTP'] = int(gt_id_count.sum() - res['IDFN'])
    res['IDR'] = res['IDTP'] / np.maximum(1.0, res['IDTP'] + res['IDFN'])
    res['IDP'] = res['IDTP'] / np.maximum(1.0, res['IDTP'] + res['IDFP'])
    res['IDF1'] = res['IDTP'] / np.maximum(1.0, res['IDTP'] + 0.5 * res['IDFP'] + 0.5 * res['IDFN'])
    return res


def hota(data):
    array_labels = np.arange(0.05, 0.99, 0.05)
    n = len(array_labels)
    res = {f: np.zeros(n) for f in ['HOTA_TP', 'HOTA_FN', 'HOTA_FP', 'LocA', 'AssA', 'AssRe',
                                    'AssPr']}
    if data['num_tracker_dets'] == 0 or data['num_gt_dets'] == 0:
        if data['num_tracker_dets'] == 0:
            res['HOTA_FN'] = data['num_gt_dets'] * np.ones(n)
        else:
            res['HOTA_FP'] = data['num_tracker_dets'] * np.ones(n)
        res['LocA'] = np.ones(n)
        return final(res)
    potential_matches_count = np.zeros((data['num_gt_ids'], data['num_tracker_ids']))
    gt_id_count = np.zeros((data['num_gt_ids'], 1))
    tracker_id_count = np.zeros((1, data['num_tracker_ids']))
    for t, (gt_ids_t, tracker_ids_t) in enumerate(zip(data['gt_ids'], data['tracker_ids'])):
        similarity = data['similarity_scores'][t]
        sim_iou_denom = similarity.sum(0)[np.newaxis, :] + similarity.sum(1)[:, np.newaxis] - similarity
        sim_iou = np.zeros_like(similarity)
        sim_iou_mask = sim_iou_denom > 0 + EPS
        sim_iou[sim_iou_mask] = similarity[sim_iou_mask] / sim_iou_denom[sim_iou_mask]
        potential_matches_count[gt_ids_t[:, np.newaxis], tracker_ids_t[np.newaxis, :]] += sim_iou
        gt_id_count[gt_ids_t] += 1
        tracker_id_count[0, tracker_ids_t] += 1
    global_alignment_score = potential_matches_count / (
        gt_id_count + tracker_id_count - potential_matches_count)
    matches_counts = [np.zeros_like(potential_matches_count) for _ in array_labels]
    for t, (gt_ids_t, tracker_ids_t) in enumerate(zip(data['gt_ids'], data['tracker_ids'])):
        if len(gt_ids_t) == 0:
            for a, alpha in enumerate(array_labels):
                res['HOTA_FP'][a] += len(tracker_ids_t)
            continue
        if len(tracker_ids_t) == 0:
            for a, alpha in enumerate(array_labels):
                res['HOTA_FN'][a] += len(gt_ids_t)
            continue
        similarity = data['similarity_scores'][t]
        score_mat = global_alignment_score[gt_ids_t[:, np.newaxis], tracker_ids_t[np.newaxis, :]] * similarity
        match_rows, match_cols = linear_sum_assignment(-score_mat)
        for a, alpha in enumerate(array_labels):
            actually_matched_mask = similarity[match_rows, match_cols] >= alpha - EPS
            alpha_match_rows = match_rows[actually_matched_mask]
            alpha_match_cols = match_cols[actually_matched_mask]
            num_matches = len(alpha_match_rows)
            res['HOTA_TP'][a] += num_matches
            res['HOTA_FN'][a] += len(gt_ids_t) - num_matches
            res['HOTA_FP'][a] += len(tracker_ids_t) - num_matches
            if num_matches > 0:
                res['LocA'][a] += sum(similarity[alpha_match_rows, alpha_match_cols])
                matches_counts[a][gt_ids_t[alpha_match_rows], tracker_ids_t[alpha_match_cols]] += 1
    for a, alpha in enumerate(array_labels):
        matches_count = matches_counts[a]
        ass_a = matches_count / np.maximum(1, gt_id_count + tracker_id_count - matches_count)
        res['AssA'][a] = np.sum(matches_count * ass_a) / np.maximum(1, res['HOTA_TP'][a])
        ass_re = matches_count / np.maximum(1, gt_id_count)
        res['AssRe'][a] = np.sum(matches_count * ass_re) / np.maximum(1, res['HOTA_TP'][a])
        ass_pr = matches_count / np.maximum(1, tracker_id_count)
        res['AssPr'][a] = np.sum(matches_count * ass_pr) / np.maximum(1, res['HOTA_TP'][a])
    res['LocA'] = np.maximum(1e-10, res['LocA']) / np.maximum(1e-10, res['HOTA_TP'])
    return final(res)


def final(res):
    res['DetRe'] = res['HOTA_TP'] / np.maximum(1, res['HOTA_TP'] + res['HOTA_FN'])
    res['DetPr'] = res['HOTA_TP'] / np.maximum(1, res['HOTA_TP'] + res['HOTA_FP'])
    res['DetA'] = res['HOTA_TP'] / np.maximum(1, res['HOTA_TP'] + res['HOTA_FN'] + res['HOTA_FP'])
    res['HOTA'] = np.sqrt(res['DetA'] * res['AssA'])
    return {k: float(np.mean(v)) for k, v in res.items()}


def single_target(frames, tid, s):
    """UAV123 precision and success, the tracked test and breaks of one target."""
    tracked_frames = 0
    errs, ious = [], []
    tracking, in_break, lost_at = False, False, 0.0
    breaks, reacq = 0, []
    for f in frames:
        truth = next((g for g in f['targets'] if g['id'] == tid), None)
        track = next((r for r in f['tracks'] if r['id'] == tid), None)
        tracked = (truth is not None and truth['visible_fraction'] >= s['min_visible_fraction']
                   and truth['box'][2] * truth['box'][3] >= s['min_box_area'])
        tracked_frames += tracked
        if truth is not None and truth['occlusion'] < 1.0:
            errs.append(centre_error(truth['box'], track['box']) if track else np.inf)
            ious.append(box_iou(truth['box'], track['box']) if track else 0.0)
        if tracking and not tracked:
            breaks += 1
            in_break, lost_at = True, f['t']
        elif in_break and tracked:
            reacq.append(f['t'] - lost_at)
            in_break = False
        tracking = tracked
    errs, ious = np.array(errs), np.array(ious)
    out = {'tracked_fraction': tracked_frames / max(1, len(frames)), 'breaks': breaks,
           'reacquired': len(reacq),
           'reacquire_median_s': float(np.median(reacq)) if reacq else 0.0,
           'reacquire_max_s': float(max(reacq)) if reacq else 0.0,
           'open_break_s': frames[-1]['t'] - lost_at if in_break else 0.0,
           'precision': 0.0, 'success': 0.0}
    if len(errs):
        out['precision'] = float(np.mean(errs <= s['precision_threshold']))
        thresholds = np.array([i / 20.0 for i in range(21)])
        out['success'] = float(np.mean([np.mean(ious > th) for th in thresholds]))
    return out


def main():
    with open(sys.argv[1]) as f:
        doc = json.load(f)
    out = []
    for seq in doc['sequences']:
        s = seq['settings']
        data = to_trackeval(seq['frames'], s['mot_min_visible_fraction'])
        c = clear(data, s['clear_threshold'])
        i = identity(data, s['clear_threshold'])
        h = hota(data)
        out.append({
            'clear': {k: float(v) for k, v in c.items() if k != 'IDSW_per_gt'},
            'idsw_per_gt': c['IDSW_per_gt'],
            'identity': {k: float(v) for k, v in i.items()},
            'hota': h,
            'targets': {tid: single_target(seq['frames'], tid, s) for tid in seq['target_ids']},
        })
    with open(sys.argv[2], 'w') as f:
        json.dump({'results': out}, f)


if __name__ == '__main__':
    main()
