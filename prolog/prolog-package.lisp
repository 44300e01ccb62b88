;;;; Package CRAM-PROLOG (nickname PROLOG): the CRAM-dialect fact engine.

(defpackage :cram-prolog
  (:nicknames :prolog)
  (:use :cl :cram-utilities)
  (:export
   ;; queries and definitions
   #:prolog #:def-fact-group #:<- #:def-prolog-handler #:remove-prolog-handler
   #:*break-on-lisp-errors* #:prolog-error #:fact-group-error #:prolog-resource-error
   #:fact-group-names #:fact-group-clauses #:remove-fact-group #:predicate-clauses
   #:add-fact #:remove-facts
   ;; native predicates
   #:def-native-predicate #:solve-continue #:unify-terms #:deref-term #:resolve-term
   ;; built-in predicate names that are not Common Lisp symbols
   #:-> #:*-> #:once #:call #:cut #:true #:fail #:bound #:ground #:==
   #:findall #:bagof #:setof #:forall #:every #:take #:lisp-fun #:lisp-pred
   #:set-symbol-value #:get-slot-value #:instance-of #:lisp-type #:subset
   #:string-concat))
