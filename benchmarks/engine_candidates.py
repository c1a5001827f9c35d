"""The training-engine candidates measured before choosing one (per mini-batch step: forward, loss, backward, Adam).

Usage::

    python benchmarks/engine_candidates.py

One (64, 64, 64) MLP step on a batch of 32, K = 1 and K = 5 members, torch single-threaded, median of 5 x 400
steps (200 for vmap and compile), all in one process:

* ``E seq``: one ``nn.Sequential`` with autograd (K = 1 only: the plain skorch module);
* ``B stacked 1grp``: per-layer ``(K, n_in, n_out)`` parameters, ``torch.baddbmm``, autograd, one Adam group;
* ``A member leaves Kgrp``: each member's own leaf parameters stacked per step, one Adam group per member;
* ``D vmap``: ``torch.func.stack_module_state`` + ``functional_call`` + ``vmap``, autograd;
* ``F compile``: ``torch.compile`` of B's forward and loss (CPU inductor);
* ``G hand no graph``: B's parameters, the forward under ``torch.no_grad`` keeping the activations and the
  backward written by hand (no autograd graph at all), gradients assigned, the same Adam step.

Printed in microseconds per step. (A hand-written backward as a custom ``autograd.Function`` was measured
the same way and was no faster than autograd's: see ``benchmarks/RESULTS.md``.)
"""
import time, statistics, torch
from torch import nn
torch.set_num_threads(1)
sizes=[6,64,64,64,7]; acts=['relu','relu','tanh','id']
def act(h,a): return torch.relu(h) if a=='relu' else torch.tanh(h) if a=='tanh' else h
def bench(step, n=400):
    for _ in range(50): step()
    ts=[]
    for r in range(5):
        t=time.perf_counter()
        for _ in range(n): step()
        ts.append((time.perf_counter()-t)/n)
    return statistics.median(ts)*1e6
def run(K):
    X=torch.randn(K,32,6); y=torch.randn(K,32,7); w=torch.ones(K,1,7)
    res={}
    # E plain sequential (K=1 reference)
    if K==1:
        m=nn.Sequential(nn.Linear(6,64),nn.ReLU(),nn.Linear(64,64),nn.ReLU(),nn.Linear(64,64),nn.Tanh(),nn.Linear(64,7))
        opt=torch.optim.Adam(m.parameters(),lr=1e-3,fused=True)
        def s():
            opt.zero_grad(); l=(((m(X[0])-y[0])**2)*w[0]).sum(1).mean(); l.backward(); opt.step()
        res['E seq']=bench(s)
    # B per-layer stacked leaves
    Ws=[torch.randn(K,a,b,requires_grad=True) for a,b in zip(sizes,sizes[1:])]
    Bs=[torch.randn(K,1,b,requires_grad=True) for b in sizes[1:]]
    opt=torch.optim.Adam(Ws+Bs,lr=1e-3,fused=True)
    def fwd(Wl,Bl):
        h=X
        for W,B,a in zip(Wl,Bl,acts): h=act(torch.baddbmm(B,h,W),a)
        return h
    def s():
        opt.zero_grad(); l=(((fwd(Ws,Bs)-y)**2)*w).sum(2).mean(1).sum(); l.backward(); opt.step()
    res['B stacked 1grp']=bench(s)
    # G the same step with the backward by hand and no graph (checked once against B's autograd gradients)
    def hand_gradients():
        with torch.no_grad():
            hs=[X]
            for W,B,a in zip(Ws,Bs,acts): hs.append(act(torch.baddbmm(B,hs[-1],W),a))
            g=2*(hs[-1]-y)*w/X.shape[1]
            for i in range(3,-1,-1):
                if acts[i]=='relu': g=g*(hs[i+1]>0)
                elif acts[i]=='tanh': g=g*(1-hs[i+1]**2)
                Ws[i].grad=torch.bmm(hs[i].transpose(1,2),g); Bs[i].grad=g.sum(1,keepdim=True)
                if i: g=torch.bmm(g,Ws[i].transpose(1,2))
    hand_gradients(); hand=[p.grad.clone() for p in Ws+Bs]
    opt.zero_grad(); (((fwd(Ws,Bs)-y)**2)*w).sum(2).mean(1).sum().backward()
    assert all(torch.allclose(a,p.grad,rtol=1e-4,atol=1e-6) for a,p in zip(hand,Ws+Bs)), 'G differs from autograd'
    def s():
        hand_gradients(); opt.step()
    res['G hand no graph']=bench(s)
    # A per-member leaves, K groups
    Wm=[[torch.randn(a,b,requires_grad=True) for a,b in zip(sizes,sizes[1:])] for k in range(K)]
    Bm=[[torch.randn(1,b,requires_grad=True) for b in sizes[1:]] for k in range(K)]
    opt2=torch.optim.Adam([{'params':Wm[k]+Bm[k]} for k in range(K)],lr=1e-3,fused=True)
    def s():
        opt2.zero_grad()
        Wl=[torch.stack([Wm[k][i] for k in range(K)]) for i in range(4)]
        Bl=[torch.stack([Bm[k][i] for k in range(K)]) for i in range(4)]
        l=(((fwd(Wl,Bl)-y)**2)*w).sum(2).mean(1).sum(); l.backward(); opt2.step()
    res['A member leaves Kgrp']=bench(s)
    # D vmap functional_call
    from torch.func import stack_module_state, functional_call
    ms=[nn.Sequential(nn.Linear(6,64),nn.ReLU(),nn.Linear(64,64),nn.ReLU(),nn.Linear(64,64),nn.Tanh(),nn.Linear(64,7)) for _ in range(K)]
    params,bufs=stack_module_state(ms)
    base=ms[0].to('meta')
    pl=list(params.values())
    opt3=torch.optim.Adam(pl,lr=1e-3,fused=True)
    def f(p,b,x): return functional_call(base,(p,b),(x,))
    vf=torch.vmap(f)
    def s():
        opt3.zero_grad(); l=(((vf(params,bufs,X)-y)**2)*w).sum(2).mean(1).sum(); l.backward(); opt3.step()
    res['D vmap']=bench(s,200)
    # F compile of B forward+loss
    try:
        def lossfn(Wl,Bl): return (((fwd(Wl,Bl)-y)**2)*w).sum(2).mean(1).sum()
        cl=torch.compile(lossfn)
        def s():
            opt.zero_grad(); l=cl(Ws,Bs); l.backward(); opt.step()
        res['F compile']=bench(s,200)
    except Exception as e: res['F compile']=repr(e)[:80]
    return res
for K in (1,5):
    print(K, {k:(round(v) if isinstance(v,float) else v) for k,v in run(K).items()}, flush=True)
