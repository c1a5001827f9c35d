"""The partly penalised ridge solver against scikit-learn's estimators (Frisch-Waugh-Lovell as the oracle)."""

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression, Ridge

from ftcal.calibrators._ridge import ridge_least_squares


def sklearn_reference(features, y, penalty, n_unpenalised):
    """Residualise on the free columns (LinearRegression), Ridge the rest, refit the free part: FWL."""
    free, penalised = features[:, :n_unpenalised], features[:, n_unpenalised:]
    both = np.hstack([y, penalised])
    residual = both - LinearRegression().fit(free, both).predict(free)
    k = y.shape[1]
    pen = Ridge(penalty, fit_intercept=False).fit(residual[:, k:], residual[:, :k]).coef_.reshape(k, -1).T
    final = LinearRegression().fit(free, y - penalised @ pen)
    return np.vstack([final.coef_.reshape(k, -1).T, pen]), final.intercept_


@pytest.mark.parametrize("penalty", [1e-6, 0.3, 50.0])
@pytest.mark.parametrize("n_unpenalised", [1, 3])
def test_matches_scikit_learn(penalty, n_unpenalised):
    rng = np.random.default_rng(1)
    features = rng.normal(size=(60, 7)) * rng.uniform(0.1, 10, size=7) + rng.normal(size=7)
    y = features @ rng.normal(size=(7, 2)) + 3.0 + 0.1 * rng.normal(size=(60, 2))
    coef, intercept = ridge_least_squares(features, y, penalty, n_unpenalised)
    ref_coef, ref_intercept = sklearn_reference(features, y, penalty, n_unpenalised)
    np.testing.assert_allclose(coef, ref_coef, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(intercept, ref_intercept, rtol=1e-7, atol=1e-9)


def test_limits_are_least_squares():
    rng = np.random.default_rng(2)
    features = rng.normal(size=(40, 4))
    y = rng.normal(size=(40, 3))
    coef, intercept = ridge_least_squares(features, y, 0.0, 2)
    ols = LinearRegression().fit(features, y)
    np.testing.assert_allclose(coef, ols.coef_.T, atol=1e-10)
    np.testing.assert_allclose(intercept, ols.intercept_, atol=1e-10)
    coef, intercept = ridge_least_squares(features, y, np.inf, 2)
    free = LinearRegression().fit(features[:, :2], y)
    assert np.all(coef[2:] == 0)
    np.testing.assert_allclose(coef[:2], free.coef_.T, atol=1e-10)
    np.testing.assert_allclose(intercept, free.intercept_, atol=1e-10)


def test_rank_deficient_free_columns_give_the_minimum_norm_solution():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(30, 1))
    features = np.hstack([a, a, rng.normal(size=(30, 2))])  # two identical unpenalised columns
    y = 2 * a + 0.5
    coef, intercept = ridge_least_squares(features, y, 1.0, 2)
    np.testing.assert_allclose(coef[:2, 0], [1.0, 1.0], atol=1e-6)  # split evenly: the minimum norm
    np.testing.assert_allclose(features @ coef + intercept, y, atol=1e-6)


@pytest.mark.parametrize("penalty", [0.0, 0.3, np.inf])
def test_groups_give_each_group_its_own_unpenalised_intercept(penalty):
    """With groups, the solver is least squares with one free intercept column per group (dummy variables, the
    oracle: the same solver with the one-hot columns placed first, unpenalised); the intercept returned is the mean
    of the groups' intercepts."""
    rng = np.random.default_rng(2)
    groups = np.repeat(np.array(["a", "b", "c", "d"]), [9, 14, 11, 16])
    onehot = (groups[:, None] == np.unique(groups)[None]).astype(float)
    features = rng.normal(size=(50, 5)) + onehot @ rng.normal(size=(4, 5))  # the groups' means differ
    y = features @ rng.normal(size=(5, 2)) + onehot @ rng.normal(size=(4, 2)) + 0.1 * rng.normal(size=(50, 2))
    coef, intercept = ridge_least_squares(features, y, penalty, n_unpenalised=2, groups=groups)
    # the oracle: dummy columns (unpenalised) + the features; a group's intercept: its dummy's coefficient + the common one
    dummy = np.hstack([onehot, features])
    ref, ref_intercept = ridge_least_squares(dummy, y, penalty, n_unpenalised=4 + 2)
    group_intercepts = ref[:4] + ref_intercept  # each group's own intercept
    np.testing.assert_allclose(coef, ref[4:], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(intercept, group_intercepts.mean(axis=0), rtol=1e-8, atol=1e-10)
