;;;; Package CRAM-PROLOG (nickname PROLOG): the CRAM-dialect fact engine.

(defpackage :cram-prolog
  (:nicknames :prolog)
  (:use :cl :cram-utilities)
  (:documentation "The CRAM-dialect fact engine.

Clauses are compiled into closures (continuation passing, variables bound destructively and
undone through a trail, first-argument indexing of every predicate,
recompiled on the first call after their fact groups change). PROLOG returns a lazy list: each
further solution resumes the solver from its choice-point stack. Deterministic tail recursion
runs in constant Lisp stack. Resource limits: a query whose heap use passes *PROLOG-HEAP-LIMIT*
(checked every few thousand predicate calls, also while FORCE-LL reads its solutions) or that
overflows the Lisp stack (terms nested hundreds of thousands deep) signals
PROLOG-RESOURCE-ERROR; the query is abandoned and the image stays usable.

Decisions on CRAM's quirks:
- == unifies (as in CRAM); EQUAL succeeds when both terms, fully substituted, are EQUAL, and
  never binds.
- -> commits to the first solution of its condition; its else branch defaults to FAIL. *->
  keeps every solution of the condition.
- A cut cuts the clause (or the query) also from inside AND, OR and the branches of -> and *->;
  NOT, ONCE, CALL, FINDALL, BAGOF, SETOF, FORALL, EVERY and the condition of -> are opaque.
- FINDALL returns an ordinary list; SETOF removes EQUAL duplicates and keeps the order of
  discovery (it does not sort), as in CRAM.
- A functor that one fact group defines may get clauses in another one only when the other one
  lists it among its extendable functors (CRAM's rule); otherwise DEF-FACT-GROUP signals
  FACT-GROUP-ERROR. A redefined group keeps its place in the clause order.
- A handler defined with DEF-PROLOG-HANDLER runs first; the functor's clauses are tried only when
  the handler returns no solution (CRAM's behaviour).
- A goal whose functor has no definition warns once per functor and fails. A goal written with a
  symbol of another package that has no definition but shares a built-in's name (CPL:FAIL, ...)
  calls that built-in.
- Lisp errors inside LISP-FUN, LISP-PRED and the other Lisp-calling built-ins warn and fail unless
  *BREAK-ON-LISP-ERRORS* is true, or the function called was registered with
  PROPAGATE-LISP-ERRORS: the functions behind predicates that change something (the Bullet
  world's assert and retract forms, SIMULATE, STEP) signal their errors out of the query, as
  CRAM's assert handlers do; query predicates keep failing. Unbound variables reach Lisp as uninterned ?symbols.
- ?symbols are variables in queries, clauses and goals given to CALL; values produced by Lisp
  code are constants, except in the binding alists a handler returns.
- Queries given as the same (constant) list are compiled once: do not modify a goal list after
  passing it to PROLOG.
- MEMBER, TAKE and LENGTH read lazy lists, computing their elements only as far as needed.
- RETE: asserted facts are data (a ?symbol in a fact is a constant; atoms compare with EQUAL). A
  production's network exists while it has handlers; handlers are called once the change that
  triggered them has propagated, so they may assert and retract facts. A Prolog pattern in a
  production is proved when a partial match reaches it; later changes of the Prolog database do
  not update its matches. ALPHA-NETWORK-SIZE counts facts.")
  (:export
   ;; queries and definitions
   #:prolog #:def-fact-group #:<- #:def-prolog-handler #:remove-prolog-handler
   #:*break-on-lisp-errors* #:propagate-lisp-errors #:lisp-errors-propagate-p
   #:*prolog-heap-limit* #:prolog-error #:fact-group-error #:prolog-resource-error
   #:fact-group-names #:fact-group-clauses #:remove-fact-group #:predicate-clauses
   #:database-generation #:filter-bindings #:unify #:unify-p #:?_
   ;; RETE: working memory and productions
   #:clear-alpha-network #:rete-assert #:rete-retract #:with-facts-asserted #:object-id
   #:rete-holds #:alpha-network-size #:rete-prove
   #:def-production #:register-production #:clear-productions #:remove-production
   #:with-productions #:register-production-handler #:remove-production-handler
   #:with-production-handlers
   #:add-fact #:remove-facts #:predicate
   ;; native predicates
   #:register-first-goal-guard
   #:def-native-predicate #:solve-continue #:unify-terms #:unify-each #:deref-term
   #:resolve-term
   ;; built-in predicate names that are not Common Lisp symbols
   #:-> #:*-> #:once #:call #:cut #:true #:fail #:bound #:ground #:==
   #:findall #:bagof #:setof #:forall #:every #:take #:lisp-fun #:lisp-pred
   #:set-symbol-value #:get-slot-value #:instance-of #:lisp-type #:subset
   #:string-concat))
