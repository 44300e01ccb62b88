;;;; Package CRAM-LANGUAGE (nickname CPL): the plan language. CRAM-LANGUAGE-IMPLEMENTATION
;;;; (CPL-IMPL) re-exports the names CRAM's implementation package shares with it
;;;; (implementation-package.lisp).

(defpackage :cram-language
  (:nicknames :cpl)
  (:use :cl)
  (:shadow #:sleep)
  (:import-from :cram-walker #:plan-tree-node #:plan-tree-node-sexp #:plan-tree-node-parent
                #:plan-tree-node-children #:plan-tree-node-path #:find-plan-node #:expand-plan)
  ;; every external symbol of COMMON-LISP (but SLEEP), so that (:use :cpl) alone is a working
  ;; package, as in CRAM
  (:export . #.(let ((names '()))
                 (do-external-symbols (s :common-lisp (sort names #'string<))
                   (unless (string= (symbol-name s) "SLEEP") (push (symbol-name s) names)))))
  (:export
   ;; tasks and plan macros
   #:top-level #:named-top-level #:seq #:par #:pursue #:try-all
   #:try-in-order #:try-each-in-order
   #:def-cram-function #:def-top-level-cram-function #:declare-goal #:def-goal
   #:*current-task* #:task #:task-name #:task-status #:task-parent
   #:current-task-p #:*inherited-specials* #:with-evaporation-deferred
   #:not-inside-plan-error #:nested-top-level-error
   #:task-exit-error #:task-exit-task-name
   #:*max-idle-task-threads* #:*idle-task-thread-name* #:stop-idle-task-threads
   #:*keep-plans-on-one-cpu* #:*plan-cpu*
   ;; the task interface
   #:status #:result #:task-dead #:task-alive #:task-running-p #:task-dead-p #:task-failed-p
   #:task-done-p #:join-task #:toplevel-task #:tagged-task #:with-tags #:partial-order
   #:suspend #:wake-up #:on-suspension #:with-task-suspended
   #:sleep* #:fl-pulsed #:fl-value-changed #:def-cpl-parameter
   #:def-plan #:def-top-level-plan
   #:plan-tree-node #:plan-tree-node-sexp #:plan-tree-node-parent #:plan-tree-node-children
   #:plan-tree-node-path #:find-plan-node #:expand-plan
   ;; failures
   #:plan-failure #:simple-plan-failure #:composite-failure #:composite-failures
   #:common-lisp-error-envelope #:envelop-error
   #:fail #:with-failure-handling #:retry
   #:with-retry-counters #:do-retry #:get-counter #:reset-counter
   ;; fluents
   #:fluent #:value-fluent #:fluent-net #:make-fluent #:fluent-name #:value
   #:wait-for #:whenever #:pulse #:pulsed #:fl-funcall #:fl-apply
   #:fl-and #:fl-or #:fl-not #:fl< #:fl> #:fl= #:fl<= #:fl>= #:fl-eq #:fl-eql
   #:fl+ #:fl- #:fl* #:fl/
   ;; time
   #:sleep #:*sleep-function* #:*ordered-concurrency* #:*ordered-start-timeout* #:with-task-waiting #:unix-time
   ;; task tree
   #:task-tree-node #:with-task-tree-node #:*task-tree-node*
   #:*last-task-tree* #:task-tree-to-json #:write-task-tree-html
   #:node-kind #:node-name #:node-designator #:node-children #:node-parent
   #:node-outcome #:node-failure #:node-caught-failures #:node-retries
   #:node-start-time #:node-end-time #:node-start-unix #:node-end-unix
   #:node-duration #:find-task-tree-nodes #:node-pictures #:note-picture
   ;; logging
   #:log-message #:log-debug #:log-info #:log-warn #:log-error
   #:*log-stream* #:*log-tags* #:*log-level* #:*log-tally* #:with-log-tags
   ;; the debugger inside plans
   #:*debug-on-lisp-errors* #:*break-on-plan-failures* #:abort-plan
   #:plan-aborted #:plan-aborted-name))
